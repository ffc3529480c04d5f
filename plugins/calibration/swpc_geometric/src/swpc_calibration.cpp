// SPDX-License-Identifier: Apache-2.0
#include "swivel/calibration/swpc_calibration.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <utility>

namespace swivel::calibration {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// Fixed-width formatting keeps the verdict text free of iostream state.
template <typename... Args>
std::string format(const char* fmt, Args... args) {
  std::array<char, 256> buf{};
  std::snprintf(buf.data(), buf.size(), fmt, args...);
  return {buf.data()};
}

// Collects the checks and remembers, per check name, every failure detail.
class VerdictBuilder {
 public:
  // Registers a check that passes unless fail() is called for it.
  void declare(const std::string& name, std::string pass_detail) {
    index_.emplace_back(name, verdict_.checks.size());
    verdict_.checks.push_back({name, true, std::move(pass_detail)});
  }

  void fail(const std::string& name, const std::string& detail) {
    QualityCheck& check = find(name);
    if (check.passed) {
      check.passed = false;
      check.detail = detail;
    } else {
      check.detail += "; " + detail;
    }
  }

  [[nodiscard]] bool passed() const { return verdict_.passed(); }
  QualityVerdict take() { return std::move(verdict_); }

 private:
  QualityCheck& find(const std::string& name) {
    for (const auto& [n, i] : index_) {
      if (n == name) return verdict_.checks[i];
    }
    declare(name, "");
    return verdict_.checks.back();
  }

  QualityVerdict verdict_;
  std::vector<std::pair<std::string, std::size_t>> index_;
};

double range_of(const std::vector<double>& v) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return *hi - *lo;
}

bool all_finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// Yaw made continuous by removing 2 pi jumps between consecutive samples.
std::vector<double> unwrap(const std::vector<double>& yaw_rad) {
  std::vector<double> out(yaw_rad.size());
  double offset = 0.0;
  for (std::size_t k = 0; k < yaw_rad.size(); ++k) {
    if (k > 0) {
      const double step = yaw_rad[k] + offset - out[k - 1];
      offset -= kTwoPi * std::round(step / kTwoPi);
    }
    out[k] = yaw_rad[k] + offset;
  }
  return out;
}

// Angle wrapped to (0, 2 pi).
double wrap_two_pi(double angle_rad) {
  double a = std::fmod(angle_rad, kTwoPi);
  if (a < 0.0) a += kTwoPi;
  return a;
}

struct SlopeFit {
  double slope = 0.0;
  double sigma = 0.0;
};

// Least-squares slope of y against x (with intercept), centred for accuracy.
SlopeFit fit_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const auto n = static_cast<double>(x.size());
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n;
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double sxx = 0.0;
  double sxy = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sxx += (x[k] - mx) * (x[k] - mx);
    sxy += (x[k] - mx) * (y[k] - my);
  }
  SlopeFit fit;
  fit.slope = sxy / sxx;
  double ssr = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double e = (y[k] - my) - fit.slope * (x[k] - mx);
    ssr += e * e;
  }
  fit.sigma = x.size() > 2 ? std::sqrt(ssr / (n - 2.0) / sxx) : 0.0;
  return fit;
}

struct PivotWithCov {
  PivotFit fit;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
};

PivotWithCov fit_pivot_cov(const std::vector<double>& x_m, const std::vector<double>& y_m,
                           const std::vector<double>& yaw_rad) {
  // W = t_k + R_k P for all k. Eliminating W leaves (sum |e_k - e_mean|^2) P =
  // sum R_k^T (t_mean - t_k), with e_k = (cos yaw_k, sin yaw_k): a scalar normal equation.
  const std::size_t n = x_m.size();
  const auto nd = static_cast<double>(n);
  std::vector<double> c(n);
  std::vector<double> s(n);
  double cm = 0.0;
  double sm = 0.0;
  double tx = 0.0;
  double ty = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    c[k] = std::cos(yaw_rad[k]);
    s[k] = std::sin(yaw_rad[k]);
    cm += c[k];
    sm += s[k];
    tx += x_m[k];
    ty += y_m[k];
  }
  cm /= nd;
  sm /= nd;
  tx /= nd;
  ty /= nd;

  double denom = 0.0;
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    denom += (c[k] - cm) * (c[k] - cm) + (s[k] - sm) * (s[k] - sm);
    const double dx = tx - x_m[k];
    const double dy = ty - y_m[k];
    rhs.x() += c[k] * dx + s[k] * dy;  // R_k^T (t_mean - t_k)
    rhs.y() += -s[k] * dx + c[k] * dy;
  }

  PivotWithCov out;
  const Eigen::Vector2d p = rhs / denom;
  // W = t_mean + R_mean P (R_mean is the mean rotation matrix, a scaled rotation).
  const Eigen::Vector2d w(tx + cm * p.x() - sm * p.y(), ty + sm * p.x() + cm * p.y());

  // Sandwich covariance: P's error is -sum (R_k - R_mean)^T e_k / denom for position errors
  // e_k, estimated per sample by the residual. Unlike sigma^2 / denom it stays right when
  // the misfit is directional (yaw noise moves the origin along one robot-frame direction).
  double ssr = 0.0;
  Eigen::Matrix2d meat = Eigen::Matrix2d::Zero();
  const std::vector<double> yaw_cont = unwrap(yaw_rad);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d r(w.x() - c[k] * p.x() + s[k] * p.y() - x_m[k],
                            w.y() - s[k] * p.x() - c[k] * p.y() - y_m[k]);
    ssr += r.squaredNorm();
    Eigen::Matrix2d dr;  // R_k - R_mean
    dr << c[k] - cm, -(s[k] - sm), s[k] - sm, c[k] - cm;
    const Eigen::Vector2d g = dr.transpose() * r;
    meat += g * g.transpose();
  }
  const double dof_scale = n > 2 ? (2.0 * nd) / (2.0 * nd - 4.0) : 1.0;
  out.cov = meat * (dof_scale / (denom * denom));
  out.fit.x_m = p.x();
  out.fit.y_m = p.y();
  out.fit.sigma_m = std::sqrt(0.5 * out.cov.trace());
  out.fit.residual_rms_m = std::sqrt(ssr / (2.0 * nd));
  out.fit.rotation_rad = n > 0 ? yaw_cont.back() - yaw_cont.front() : 0.0;
  return out;
}

using GeometryInputs = Eigen::Matrix<double, 6, 1>;   // P1x, P1y, P2x, P2y, phi1m, phi2m
using GeometryOutputs = Eigen::Matrix<double, 4, 1>;  // Sx, Sy, d, delta

GeometryOutputs geometry(const GeometryInputs& in) {
  const AxisGeometry g = steering_axis_from_pivots(in(0), in(1), in(2), in(3), in(4), in(5));
  return {g.x_m, g.y_m, g.caster_offset_m, g.steering_offset_rad};
}

// Central-difference Jacobian of the closed-form geometry; delta's difference is wrapped so
// that an offset near +-pi does not jump.
Eigen::Matrix<double, 4, 6> geometry_jacobian(const GeometryInputs& in) {
  Eigen::Matrix<double, 4, 6> jac;
  for (int i = 0; i < 6; ++i) {
    const double h = 1e-7;
    GeometryInputs lo = in;
    GeometryInputs hi = in;
    lo(i) -= h;
    hi(i) += h;
    GeometryOutputs diff = geometry(hi) - geometry(lo);
    diff(3) = wrap_pi(diff(3));
    jac.col(i) = diff / (2.0 * h);
  }
  return jac;
}

struct Runs {
  std::size_t first = 0;
  std::size_t second = 0;
};

}  // namespace

double wrap_pi(double angle_rad) {
  double a = std::fmod(angle_rad + kPi, kTwoPi);
  if (a <= 0.0) a += kTwoPi;
  return a - kPi;
}

bool QualityVerdict::passed() const {
  return std::all_of(checks.begin(), checks.end(), [](const QualityCheck& c) { return c.passed; });
}

std::string QualityVerdict::text() const {
  std::string out;
  for (const QualityCheck& c : checks) {
    out += (c.passed ? "PASS " : "FAIL ") + c.name + ": " + c.detail + "\n";
  }
  return out;
}

std::string QualityVerdict::failure_reason() const {
  std::string out;
  for (const QualityCheck& c : checks) {
    if (c.passed) continue;
    if (!out.empty()) out += "; ";
    out += c.name + ": " + c.detail;
  }
  return out;
}

PivotFit fit_pivot(const std::vector<double>& x_m, const std::vector<double>& y_m,
                   const std::vector<double>& yaw_rad) {
  return fit_pivot_cov(x_m, y_m, yaw_rad).fit;
}

AxisGeometry steering_axis_from_pivots(double p1_x_m, double p1_y_m, double p2_x_m, double p2_y_m,
                                       double phi1_meas_rad, double phi2_meas_rad) {
  const double dphi = wrap_two_pi(phi2_meas_rad - phi1_meas_rad);
  const double chord = 2.0 * std::sin(0.5 * dphi);  // > 0 on (0, 2 pi)
  const double bx = p2_x_m - p1_x_m;
  const double by = p2_y_m - p1_y_m;
  // Apex of the isosceles triangle: P1->P2 turned counter-clockwise by (pi - dphi)/2 and
  // scaled to length d = |P1P2| / chord.
  const double a = 0.5 * (kPi - dphi);
  const double ca = std::cos(a);
  const double sa = std::sin(a);
  AxisGeometry g;
  g.caster_offset_m = std::hypot(bx, by) / chord;
  g.x_m = p1_x_m + (ca * bx - sa * by) / chord;
  g.y_m = p1_y_m + (sa * bx + ca * by) / chord;
  // S->P1 = -d u1, so the true angle at P1 is angle(S->P1) - pi.
  const double true1 = std::atan2(p1_y_m - g.y_m, p1_x_m - g.x_m) - kPi;
  g.steering_offset_rad = wrap_pi(true1 - phi1_meas_rad);
  return g;
}

CalibrationResult calibrate(const CalibrationInput& input, const CalibrationOptions& options) {
  CalibrationResult result;
  VerdictBuilder vb;
  const std::size_t n = input.module_count;

  vb.declare("input_structure", format("%zu modules, %zu runs", n, input.runs.size()));
  if (n < 2) vb.fail("input_structure", format("need at least 2 modules, got %zu", n));
  std::vector<Runs> runs_of(n);
  std::vector<int> run_count(n, 0);
  for (std::size_t j = 0; j < input.runs.size(); ++j) {
    const LockedRun& run = input.runs[j];
    if (run.locked_module >= n) {
      vb.fail("input_structure",
              format("run %zu locks module %zu of %zu", j + 1, run.locked_module + 1, n));
      continue;
    }
    const std::size_t m = run.locked_module;
    if (run_count[m] == 0) runs_of[m].first = j;
    if (run_count[m] == 1) runs_of[m].second = j;
    ++run_count[m];
    const RunSeries& d = run.data;
    const std::size_t k = d.t_s.size();
    bool sizes_ok = d.x_m.size() == k && d.y_m.size() == k && d.yaw_rad.size() == k &&
                    d.wheel_angle_rad.size() == n &&
                    (d.steer_angle_rad.empty() || d.steer_angle_rad.size() == n);
    for (const auto& w : d.wheel_angle_rad) sizes_ok = sizes_ok && w.size() == k;
    for (const auto& s : d.steer_angle_rad) sizes_ok = sizes_ok && s.size() == k;
    if (!sizes_ok) {
      vb.fail("input_structure",
              format("run %zu (module %zu locked): series lengths differ or not one series per "
                     "module",
                     j + 1, m + 1));
    } else if (k < options.min_samples) {
      vb.fail("input_structure", format("run %zu (module %zu locked): %zu samples, need %zu", j + 1,
                                        m + 1, k, options.min_samples));
    }
  }
  for (std::size_t m = 0; m < n; ++m) {
    if (run_count[m] != 2) {
      vb.fail("input_structure",
              format("module %zu has %d locked runs, need exactly 2", m + 1, run_count[m]));
    }
  }
  if (!vb.passed()) {
    result.verdict = vb.take();
    return result;
  }

  vb.declare("finite_inputs", "every sample finite");
  for (std::size_t j = 0; j < input.runs.size(); ++j) {
    const LockedRun& run = input.runs[j];
    const RunSeries& d = run.data;
    bool finite = std::isfinite(run.locked_steer_meas_rad) && all_finite(d.t_s) &&
                  all_finite(d.x_m) && all_finite(d.y_m) && all_finite(d.yaw_rad);
    for (const auto& w : d.wheel_angle_rad) finite = finite && all_finite(w);
    for (const auto& s : d.steer_angle_rad) finite = finite && all_finite(s);
    if (!finite) {
      vb.fail("finite_inputs", format("run %zu (module %zu locked) holds a non-finite value", j + 1,
                                      run.locked_module + 1));
      continue;
    }
    for (std::size_t k = 1; k < d.t_s.size(); ++k) {
      if (!(d.t_s[k] > d.t_s[k - 1])) {
        vb.fail("finite_inputs", format("run %zu (module %zu locked): time not increasing at "
                                        "sample %zu",
                                        j + 1, run.locked_module + 1, k));
        break;
      }
    }
  }
  if (!vb.passed()) {
    result.verdict = vb.take();
    return result;
  }

  // Per run: rotation, pivot, every free wheel turning, the lock held.
  vb.declare("enough_rotation",
             format("every run turns at least %.1f deg", options.min_rotation_rad * kRadToDeg));
  vb.declare("pivot_fit", format("pivot residual RMS below %.3f mm in every run",
                                 options.max_pivot_residual_rms_m * 1e3));
  vb.declare("modules_moved",
             format("every free wheel turned at least %.2f rad", options.min_wheel_rotation_rad));
  vb.declare("lock_held", "locked wheel and steering still");
  vb.declare("free_casters_settled", "free steering angles steady");
  vb.declare("locked_angles_distinct",
             format("locked angles of every module differ by %.1f..%.1f deg",
                    options.min_locked_angle_separation_rad * kRadToDeg,
                    360.0 - options.min_locked_angle_separation_rad * kRadToDeg));

  std::vector<PivotWithCov> pivots(input.runs.size());
  std::vector<std::vector<double>> theta(input.runs.size());
  double worst_rms = 0.0;
  for (std::size_t j = 0; j < input.runs.size(); ++j) {
    const LockedRun& run = input.runs[j];
    const RunSeries& d = run.data;
    const std::size_t lm = run.locked_module;
    theta[j] = unwrap(d.yaw_rad);
    const double rotation = range_of(theta[j]);
    if (rotation < options.min_rotation_rad) {
      vb.fail("enough_rotation",
              format("module %zu locked at %.2f deg turned only %.2f deg (need %.1f)", lm + 1,
                     run.locked_steer_meas_rad * kRadToDeg, rotation * kRadToDeg,
                     options.min_rotation_rad * kRadToDeg));
      continue;  // the pivot is not determined
    }
    pivots[j] = fit_pivot_cov(d.x_m, d.y_m, d.yaw_rad);
    worst_rms = std::max(worst_rms, pivots[j].fit.residual_rms_m);
    if (!(pivots[j].fit.residual_rms_m <= options.max_pivot_residual_rms_m)) {
      vb.fail("pivot_fit",
              format("module %zu locked at %.2f deg: residual RMS %.3f mm (limit "
                     "%.3f mm): the robot did not turn about a fixed point",
                     lm + 1, run.locked_steer_meas_rad * kRadToDeg,
                     pivots[j].fit.residual_rms_m * 1e3, options.max_pivot_residual_rms_m * 1e3));
    }
    for (std::size_t m = 0; m < n; ++m) {
      const double wheel_range = range_of(d.wheel_angle_rad[m]);
      if (m == lm) {
        if (wheel_range > options.max_locked_wheel_motion_rad) {
          vb.fail("lock_held",
                  format("locked module %zu's wheel moved %.4f rad", m + 1, wheel_range));
        }
        if (!d.steer_angle_rad.empty() &&
            range_of(d.steer_angle_rad[m]) > options.max_locked_steer_motion_rad) {
          vb.fail("lock_held", format("locked module %zu's steering moved %.3f deg", m + 1,
                                      range_of(d.steer_angle_rad[m]) * kRadToDeg));
        }
        continue;
      }
      if (!(wheel_range >= options.min_wheel_rotation_rad)) {
        vb.fail("modules_moved",
                format("module %zu's wheel turned %.4f rad while module %zu was locked", m + 1,
                       wheel_range, lm + 1));
      }
      if (!d.steer_angle_rad.empty() &&
          range_of(d.steer_angle_rad[m]) > options.max_free_steer_motion_rad) {
        vb.fail("free_casters_settled",
                format("module %zu's steering swept %.2f deg while module %zu was locked", m + 1,
                       range_of(d.steer_angle_rad[m]) * kRadToDeg, lm + 1));
      }
    }
  }
  for (std::size_t m = 0; m < n; ++m) {
    const double phi1 = input.runs[runs_of[m].first].locked_steer_meas_rad;
    const double phi2 = input.runs[runs_of[m].second].locked_steer_meas_rad;
    const double dphi = wrap_two_pi(phi2 - phi1);
    if (dphi < options.min_locked_angle_separation_rad ||
        dphi > kTwoPi - options.min_locked_angle_separation_rad) {
      vb.fail("locked_angles_distinct",
              format("module %zu locked at %.2f and %.2f deg: difference too small for eq. (1)",
                     m + 1, phi1 * kRadToDeg, phi2 * kRadToDeg));
    }
  }
  if (!vb.passed()) {
    result.verdict = vb.take();
    return result;
  }

  // Pass 1: steering axis, caster offset and steering offset of every module.
  vb.declare("geometry", "pivots distinct and every free contact point off the pivot");
  std::vector<ModuleCalibration> modules(n);
  std::vector<Eigen::Matrix3d> axis_cov(n);  // over (Sx, Sy, d)
  for (std::size_t m = 0; m < n; ++m) {
    const PivotWithCov& a = pivots[runs_of[m].first];
    const PivotWithCov& b = pivots[runs_of[m].second];
    GeometryInputs in;
    in << a.fit.x_m, a.fit.y_m, b.fit.x_m, b.fit.y_m,
        input.runs[runs_of[m].first].locked_steer_meas_rad,
        input.runs[runs_of[m].second].locked_steer_meas_rad;
    const double sep = std::hypot(b.fit.x_m - a.fit.x_m, b.fit.y_m - a.fit.y_m);
    const double sep_sigma = std::sqrt(a.cov.trace() + b.cov.trace());
    if (!(sep > 1e-9) || !(sep > 5.0 * sep_sigma)) {
      vb.fail("geometry", format("module %zu's two pivots are %.4f mm apart (1-sigma %.4f mm): "
                                 "the caster offset is not observable",
                                 m + 1, sep * 1e3, sep_sigma * 1e3));
      continue;
    }
    const GeometryOutputs out = geometry(in);
    Eigen::Matrix<double, 6, 6> in_cov = Eigen::Matrix<double, 6, 6>::Zero();
    in_cov.block<2, 2>(0, 0) = a.cov;
    in_cov.block<2, 2>(2, 2) = b.cov;
    in_cov(4, 4) = in_cov(5, 5) = options.steer_encoder_sigma_rad * options.steer_encoder_sigma_rad;
    const Eigen::Matrix<double, 4, 6> jac = geometry_jacobian(in);
    const Eigen::Matrix4d out_cov = jac * in_cov * jac.transpose();

    ModuleCalibration& mc = modules[m];
    mc.params.x_m = out(0);
    mc.params.y_m = out(1);
    mc.params.caster_offset_m = out(2);
    mc.params.steering_offset_rad = out(3);
    mc.sigma.x_m = std::sqrt(out_cov(0, 0));
    mc.sigma.y_m = std::sqrt(out_cov(1, 1));
    mc.sigma.caster_offset_m = std::sqrt(out_cov(2, 2));
    mc.sigma.steering_offset_rad = std::sqrt(out_cov(3, 3));
    mc.pivot1 = a.fit;
    mc.pivot2 = b.fit;
    axis_cov[m] = out_cov.block<3, 3>(0, 0);
  }
  if (!vb.passed()) {
    result.verdict = vb.take();
    return result;
  }

  // Pass 2: wheel radii, eq. (4), from every run in which the module was free.
  struct Estimate {
    double value_m;
    double slope;
    double slope_sigma;
    double arm_m;
    Eigen::Vector3d d_arm;    // dL / d(Sx, Sy, d) of the free module
    double arm_var_pivot_m2;  // from the pivot's own covariance
  };
  std::vector<std::vector<Estimate>> estimates(n);
  for (std::size_t j = 0; j < input.runs.size(); ++j) {
    const LockedRun& run = input.runs[j];
    const PivotWithCov& pv = pivots[j];
    for (std::size_t m = 0; m < n; ++m) {
      if (m == run.locked_module) continue;
      const SwpcModuleParams& p = modules[m].params;
      const Eigen::Vector2d to_axis(p.x_m - pv.fit.x_m, p.y_m - pv.fit.y_m);
      const double arm2 = to_axis.squaredNorm() - p.caster_offset_m * p.caster_offset_m;
      if (!(arm2 > 0.0)) {
        vb.fail("geometry", format("module %zu's steering axis lies within its caster offset of "
                                   "module %zu's pivot",
                                   m + 1, run.locked_module + 1));
        continue;
      }
      const double arm = std::sqrt(arm2);
      std::vector<double> psi(run.data.wheel_angle_rad[m]);
      const double psi0 = psi.front();
      for (double& v : psi) v -= psi0;
      const SlopeFit sf = fit_slope(psi, theta[j]);
      Estimate e{};
      e.slope = std::abs(sf.slope);
      e.slope_sigma = sf.sigma;
      e.arm_m = arm;
      e.value_m = arm * e.slope;
      const Eigen::Vector2d g = to_axis / arm;
      e.d_arm << g.x(), g.y(), -p.caster_offset_m / arm;
      e.arm_var_pivot_m2 = g.dot(pv.cov * g);
      estimates[m].push_back(e);
    }
  }
  if (!vb.passed()) {
    result.verdict = vb.take();
    return result;
  }

  vb.declare("wheel_radius_consistency", format("repeated r estimates agree within %.1f %%",
                                                options.max_r_relative_spread * 100.0));
  double worst_spread = 0.0;
  for (std::size_t m = 0; m < n; ++m) {
    const std::vector<Estimate>& es = estimates[m];
    const auto count = static_cast<double>(es.size());
    double mean = 0.0;
    double lo = es.front().value_m;
    double hi = lo;
    for (const Estimate& e : es) {
      mean += e.value_m;
      lo = std::min(lo, e.value_m);
      hi = std::max(hi, e.value_m);
      modules[m].wheel_radius_estimates_m.push_back(e.value_m);
    }
    mean /= count;
    double sample_var = 0.0;
    for (const Estimate& e : es) sample_var += (e.value_m - mean) * (e.value_m - mean);
    sample_var = es.size() > 1 ? sample_var / (count - 1.0) : 0.0;
    const double spread = (hi - lo) / mean;
    worst_spread = std::max(worst_spread, spread);
    if (!(spread <= options.max_r_relative_spread)) {
      vb.fail("wheel_radius_consistency",
              format("module %zu's %zu r estimates span %.3f..%.3f mm (%.2f %%)", m + 1, es.size(),
                     lo * 1e3, hi * 1e3, spread * 100.0));
    }
    // The module's own axis and offset errors are common to all its estimates; pivot and
    // slope errors are independent per run. The spread of the estimates measures the
    // independent part empirically, which also catches effects the model leaves out (slip).
    Eigen::Vector3d common_grad = Eigen::Vector3d::Zero();
    double independent_var = 0.0;
    for (const Estimate& e : es) {
      common_grad += e.slope * e.d_arm / count;
      independent_var += (e.slope * e.slope * e.arm_var_pivot_m2 +
                          e.arm_m * e.arm_m * e.slope_sigma * e.slope_sigma) /
                         (count * count);
    }
    const double common_var = common_grad.dot(axis_cov[m] * common_grad);
    modules[m].params.wheel_radius_m = mean;
    modules[m].sigma.wheel_radius_m =
        std::sqrt(common_var + std::max(independent_var, sample_var / count));
  }
  QualityVerdict verdict = vb.take();
  for (QualityCheck& c : verdict.checks) {
    if (c.name == "pivot_fit" && c.passed) {
      c.detail += format(" (worst %.4f mm)", worst_rms * 1e3);
    } else if (c.name == "wheel_radius_consistency" && c.passed) {
      c.detail += format(" (worst %.4f %%)", worst_spread * 100.0);
    }
  }
  result.verdict = std::move(verdict);
  if (result.verdict.passed()) result.modules = std::move(modules);
  return result;
}

}  // namespace swivel::calibration
