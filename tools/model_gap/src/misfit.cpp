// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/misfit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "swivel/model_gap/fit.hpp"

namespace swivel::model_gap {
namespace {

// Robust z above which one window is a jump rather than noise (a Gaussian window exceeds
// it once in 10^15). One such window alone may be a glitch of the replay (a caster, a
// command step at an unlucky instant); jumps are reported from two on, or one far out.
constexpr double kJumpZ = 8.0;
constexpr double kLoneJumpZ = 20.0;
// A window that alone fixes a coefficient (leverage 1) gives it no evidence of its
// uncertainty: its residual is scaled by at most 1 / 0.05.
constexpr double kMinOneMinusLeverage = 0.05;

// Regression of whitened residuals y on whitened regressors X (rows x p, row-major) with a
// autocorrelation-robust Wald test of all coefficients; rows with a non-finite value are skipped.
struct Regression {
  double z = 0.0;
  double share = 0.0;
  double size = 0.0;      // RMS of the fitted part over the RMS of what is left around it
  std::vector<double> t;  ///< per coefficient: estimate over its standard deviation
};

double median_abs(std::vector<double> v);

// median_abs() of the finite values of `v`.
double median_abs_finite(const std::vector<double>& v) {
  std::vector<double> finite;
  for (double x : v) {
    if (std::isfinite(x)) finite.push_back(x);
  }
  return finite.empty() ? 0.0 : median_abs(finite);
}

Regression regress(const std::vector<double>& y, const std::vector<double>& x, std::size_t p,
                   const std::vector<std::size_t>& window, const std::vector<std::size_t>& group,
                   std::size_t windows) {
  Regression out;
  const std::size_t n = y.size();
  const auto pp = static_cast<Eigen::Index>(p);
  Eigen::MatrixXd xtx = Eigen::MatrixXd::Zero(pp, pp);
  Eigen::VectorXd xty = Eigen::VectorXd::Zero(pp);
  double yty = 0.0;
  std::size_t used = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(y[i])) continue;
    const Eigen::Map<const Eigen::VectorXd> row(x.data() + i * p, pp);
    if (!row.allFinite()) continue;
    xtx.noalias() += row * row.transpose();
    xty += row * y[i];
    yty += y[i] * y[i];
    ++used;
  }
  if (used < 3 * p + 5 || yty <= 0.0) return out;
  const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> decomposition(xtx);
  const Eigen::VectorXd beta = decomposition.solve(xty);
  const Eigen::MatrixXd xtx_inverse = decomposition.pseudoInverse();
  std::vector<double> r(n, std::numeric_limits<double>::quiet_NaN());
  // Each residual over one minus its row's leverage (HC3): a window that pulls the fit
  // through itself leaves a small residual, and the covariance, built from residuals, would
  // otherwise take the pattern it made for a certain one. On a run of a few dozen windows the
  // plain sandwich put 0.5 % of pure-noise tests above 5 sigma.
  std::vector<double> r_scores(n, std::numeric_limits<double>::quiet_NaN());
  std::vector<double> jac(n * p, 0.0);
  double rss = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(y[i])) continue;
    const Eigen::Map<const Eigen::VectorXd> row(x.data() + i * p, pp);
    if (!row.allFinite()) continue;
    r[i] = y[i] - row.dot(beta);
    rss += r[i] * r[i];
    const double leverage = row.dot(xtx_inverse * row);
    r_scores[i] = r[i] / std::max(1.0 - leverage, kMinOneMinusLeverage);
    for (std::size_t k = 0; k < p; ++k) jac[i * p + k] = -x[i * p + k];
  }
  std::vector<char> observable;
  std::vector<double> effective_windows;
  // No lagged scores: HC3 and F on few windows are what keeps these tests quiet on clean runs,
  // and they were measured on the windows' scores alone.
  const std::vector<double> cov = sandwich_covariance(jac, p, r_scores, window, group, windows,
                                                      observable, false, 0, &effective_windows);
  std::vector<double> b(p);
  for (std::size_t k = 0; k < p; ++k) b[k] = beta(static_cast<Eigen::Index>(k));
  std::size_t rank = 0;
  const double chi2 = mahalanobis_squared(b, cov, rank);
  // The covariance is estimated from the windows themselves: F, not chi-square, on the
  // fewest windows any coefficient's variance rests on (few when a regressor lives in a few
  // windows: acceleration at a handful of command steps).
  out.z = rank > 0
              ? wald_f_z(chi2, static_cast<double>(rank), fewest_windows(effective_windows, 0, p))
              : 0.0;
  out.share = std::clamp(1.0 - rss / yty, 0.0, 1.0);
  // Against the noise left around the pattern, not the modelled noise: a noise model fitted
  // to these residuals has taken in part of the pattern itself.
  out.size = rss > 0.0 ? std::sqrt(std::max(0.0, yty - rss) / rss) : 0.0;
  out.t.resize(p);
  for (std::size_t k = 0; k < p; ++k) {
    const double var = cov[k * p + k];
    out.t[k] = var > 0.0 ? b[k] / std::sqrt(var) : 0.0;
  }

  return out;
}

double median_abs(std::vector<double> v) {
  if (v.empty()) return 0.0;
  for (double& x : v) x = std::abs(x);
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// A test's result without jump windows (every test's but the jumps').
MisfitTest result(std::string test, const std::string& channel, std::string label, double z,
                  double share, double size, std::size_t module) {
  MisfitTest m;
  m.test = std::move(test);
  m.channel = channel;
  m.label = std::move(label);
  m.z = z;
  m.share = share;
  m.size = size;
  m.module = module;
  return m;
}

// A caster whose steering axis the commands carry less than this many caster offsets over a
// window, at their slowest there, barely rolls: its tyre, not its servo, holds its angle,
// and what the servo was held off by can be let go within that window.
constexpr double kBarelyRollsOffsets = 2.0;

// How many of `jumps` in channel `info` lie in a window where its caster barely rolls (0 for
// other channels).
std::size_t jumps_where_caster_barely_rolls(const MisfitInputs& in, const ChannelInfo& info,
                                            const std::vector<MisfitTest::Span>& jumps) {
  if (info.kind != ChannelKind::kSteerAngle || info.module >= in.slowest_roll_offsets.size())
    return 0;
  const std::vector<double>& roll = in.slowest_roll_offsets[info.module];
  return static_cast<std::size_t>(
      std::count_if(jumps.begin(), jumps.end(), [&roll](const MisfitTest::Span& span) {
        for (std::size_t j = span.first; j < span.first + span.count && j < roll.size(); ++j) {
          if (roll[j] < kBarelyRollsOffsets) return true;
        }
        return false;
      }));
}

std::string jumps_label(std::size_t count, std::size_t barely_rolling) {
  if (count == 0) return "no jumps";
  std::string label = std::to_string(count) + " isolated jump" + (count > 1 ? "s" : "");
  if (barely_rolling == count)
    return label + (count > 1 ? ", all" : ",") + " where its caster barely rolls";
  if (barely_rolling > 0)
    return label + ", " + std::to_string(barely_rolling) + " where its caster barely rolls";
  return label;
}

// Jumps: windows far outside the channel's robust spread (none when the channel has fewer
// than 10 finite windows). A transient that the run and the replay place a little apart in
// time moves residual from one window into the next: two neighbours, one of them far out,
// that mostly cancel. What the model got wrong there is their sum, which is what counts. Both
// are taken in the channel's units, and the sum is whitened by the two windows' noise
// together: a caster's transient often straddles a window of much steering (noisier) and a
// quiet one, and whitened one by one the same rotation would not cancel.
void jumps_test(const MisfitInputs& in, std::size_t c, const std::vector<double>& y,
                std::vector<MisfitTest>& out) {
  const ChannelInfo& info = in.channels[c];
  const std::size_t w = y.size();
  const double* residual = in.residuals.data() + c * w;
  const double* sigma = in.sigma.data() + c * w;
  std::vector<double> finite;
  std::vector<MisfitTest::Span> spans;  // per entry of `finite`
  const double far = kJumpZ * std::max(1.4826 * median_abs_finite(y), 1.0);
  for (std::size_t j = 0; j < w; ++j) {
    const double v = y[j];
    if (!std::isfinite(v)) continue;
    const double next = j + 1 < w ? y[j + 1] : std::numeric_limits<double>::quiet_NaN();
    if (std::isfinite(next) && std::max(std::abs(v), std::abs(next)) > far) {
      const double sum = residual[j] + residual[j + 1];
      if (std::abs(sum) < 0.5 * std::max(std::abs(residual[j]), std::abs(residual[j + 1]))) {
        finite.push_back(sum / std::hypot(sigma[j], sigma[j + 1]));
        spans.push_back({j, 2});
        ++j;
        continue;
      }
    }
    finite.push_back(v);
    spans.push_back({j, 1});
  }
  // A jump stands out of the channel's robust spread and of its modelled noise alike (a
  // channel quieter than its model, say quantized to whole counts, has a tiny spread).
  const double spread = std::max(1.4826 * median_abs(finite), 1.0);
  if (!(spread > 0.0 && finite.size() >= 10)) return;
  std::vector<double> z;
  z.reserve(finite.size());
  MisfitTest test = result("jumps", info.name, "", 0.0, 0.0, 0.0, info.module);
  for (std::size_t k = 0; k < finite.size(); ++k) {
    z.push_back(std::abs(finite[k]) / spread);
    if (z.back() > kJumpZ) test.jumps.push_back(spans[k]);
  }
  std::sort(z.begin(), z.end(), std::greater<>());
  const std::size_t count = test.jumps.size();
  // The second largest decides (or the largest alone, against the higher bar); reported on
  // the scale of the other tests: 5 at the bar.
  const double second = z.size() > 1 ? z[1] : 0.0;
  const double strength = std::max(second / kJumpZ, z[0] / kLoneJumpZ);
  test.label = jumps_label(count, jumps_where_caster_barely_rolls(in, info, test.jumps));
  test.z = 5.0 * strength;
  test.size = strength * kJumpZ;
  out.push_back(std::move(test));
}

// The windows' indices, each its own window for the covariance, all in one group.
struct WindowRows {
  explicit WindowRows(std::size_t w) : window(w), one_group(w, 0) {
    for (std::size_t j = 0; j < w; ++j) window[j] = j;
  }
  std::vector<std::size_t> window;
  std::vector<std::size_t> one_group;
};

// Trend: a constant rate, the channel's own motion (signed and absolute) and the
// acceleration.
MisfitTest trend_test(const MisfitInputs& in, std::size_t c, const std::vector<double>& y,
                      const WindowRows& rows) {
  const std::size_t w = in.windows;
  constexpr std::size_t kTrend = 4;
  std::vector<double> x(w * kTrend);
  for (std::size_t j = 0; j < w; ++j) {
    const double s = in.sigma[c * w + j];
    const double m = in.own_change[c * w + j];
    x[j * kTrend + 0] = 1.0 / s;
    x[j * kTrend + 1] = m / s;
    x[j * kTrend + 2] = std::abs(m) / s;
    x[j * kTrend + 3] = in.accel[j] / s;
  }
  const Regression trend = regress(y, x, kTrend, rows.window, rows.one_group, w);
  static constexpr const char* kTrendLabels[kTrend] = {
      "grows with time", "grows with its own motion", "grows with the amount of motion",
      "grows with acceleration"};
  std::size_t strongest = 0;
  for (std::size_t k = 1; k < trend.t.size(); ++k) {
    if (std::abs(trend.t[k]) > std::abs(trend.t[strongest])) strongest = k;
  }
  const ChannelInfo& info = in.channels[c];
  return result("trend", info.name, trend.t.empty() ? "irregular" : kTrendLabels[strongest],
                trend.z, trend.share, trend.size, info.module);
}

// Repeats with a wheel's turn: for each wheel, the change of sin and cos of its angle.
void wheel_periodic_tests(const MisfitInputs& in, std::size_t c, const std::vector<double>& y,
                          const WindowRows& rows, std::vector<MisfitTest>& out) {
  const std::size_t w = in.windows;
  for (std::size_t i = 0; i < in.wheel_sin_change.size(); ++i) {
    std::vector<double> xw(w * 2);
    for (std::size_t j = 0; j < w; ++j) {
      const double s = in.sigma[c * w + j];
      xw[j * 2 + 0] = in.wheel_sin_change[i][j] / s;
      xw[j * 2 + 1] = in.wheel_cos_change[i][j] / s;
    }
    const Regression periodic = regress(y, xw, 2, rows.window, rows.one_group, w);
    out.push_back(result("wheel_periodic", in.channels[c].name,
                         "repeats with wheel " + std::to_string(i + 1) + "'s turn", periodic.z,
                         periodic.share, periodic.size, i));
  }
}

// World drift: the displacement residual turned into the world frame has a constant part
// (the first pair of position channels; none without one).
void world_drift_test(const MisfitInputs& in, std::vector<MisfitTest>& out) {
  const std::size_t w = in.windows;
  std::size_t cx = in.channels.size();
  for (std::size_t c = 0; c + 1 < in.channels.size(); ++c) {
    if (in.channels[c].kind == ChannelKind::kPosition &&
        in.channels[c + 1].kind == ChannelKind::kPosition) {
      cx = c;
      break;
    }
  }
  if (cx >= in.channels.size()) return;
  // Two rows per window (world x and y), both in the same window for the covariance.
  std::vector<double> y(2 * w);
  std::vector<double> x(2 * w * 2, 0.0);
  std::vector<std::size_t> rows_window(2 * w);
  std::vector<std::size_t> rows_axis(2 * w);
  for (std::size_t j = 0; j < w; ++j) {
    const double rx = in.residuals[cx * w + j];
    const double ry = in.residuals[(cx + 1) * w + j];
    const double s = std::sqrt(0.5 * (in.sigma[cx * w + j] * in.sigma[cx * w + j] +
                                      in.sigma[(cx + 1) * w + j] * in.sigma[(cx + 1) * w + j]));
    const double c = std::cos(in.start_yaw_rad[j]);
    const double sn = std::sin(in.start_yaw_rad[j]);
    y[2 * j] = (c * rx - sn * ry) / s;
    y[2 * j + 1] = (sn * rx + c * ry) / s;
    x[(2 * j) * 2 + 0] = 1.0 / s;
    x[(2 * j + 1) * 2 + 1] = 1.0 / s;
    rows_window[2 * j] = j;
    rows_window[2 * j + 1] = j;
    rows_axis[2 * j] = 0;
    rows_axis[2 * j + 1] = 1;
  }
  const Regression drift = regress(y, x, 2, rows_window, rows_axis, w);
  out.push_back(result("world_drift", in.channels[cx].name, "drifts in a fixed world direction",
                       drift.z, drift.share, drift.size, 0));
}

}  // namespace

std::vector<MisfitTest> misfit_tests(const MisfitInputs& in) {
  std::vector<MisfitTest> out;
  const std::size_t w = in.windows;
  const WindowRows rows(w);
  for (std::size_t c = 0; c < in.channels.size(); ++c) {
    std::vector<double> y(w);
    for (std::size_t j = 0; j < w; ++j) y[j] = in.residuals[c * w + j] / in.sigma[c * w + j];
    jumps_test(in, c, y, out);
    out.push_back(trend_test(in, c, y, rows));
    wheel_periodic_tests(in, c, y, rows, out);
  }
  world_drift_test(in, out);
  std::sort(out.begin(), out.end(),
            [](const MisfitTest& a, const MisfitTest& b) { return a.z > b.z; });
  return out;
}

}  // namespace swivel::model_gap
