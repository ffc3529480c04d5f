#include "swivel/model_gap/locate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace swivel::model_gap {
namespace {

// Centred difference over a window so that a command step reads as a short acceleration
// rather than one infinite sample.
std::vector<double> smoothed_derivative(const std::vector<double>& t, const std::vector<double>& v,
                                        double window_s) {
  const std::size_t n = t.size();
  std::vector<double> d(n, 0.0);
  if (n < 2) return d;
  std::size_t lo = 0;
  std::size_t hi = 0;
  for (std::size_t k = 0; k < n; ++k) {
    while (lo < k && t[k] - t[lo] > 0.5 * window_s) ++lo;
    while (hi + 1 < n && t[hi + 1] - t[k] <= 0.5 * window_s) ++hi;
    const double dt = t[hi] - t[lo];
    d[k] = dt > 0.0 ? (v[hi] - v[lo]) / dt : 0.0;
  }
  return d;
}

struct LineFit {
  double slope = 0.0;
  double r_squared = 0.0;
};

// Least squares r = a + b s over the finite samples.
LineFit fit_line(const std::vector<double>& r, const std::vector<double>& s) {
  double n = 0.0;
  double ms = 0.0;
  double mr = 0.0;
  for (std::size_t k = 0; k < r.size(); ++k) {
    if (!std::isfinite(r[k]) || !std::isfinite(s[k])) continue;
    n += 1.0;
    ms += s[k];
    mr += r[k];
  }
  if (n < 3.0) return {};
  ms /= n;
  mr /= n;
  double sss = 0.0;
  double ssr = 0.0;
  double srs = 0.0;
  for (std::size_t k = 0; k < r.size(); ++k) {
    if (!std::isfinite(r[k]) || !std::isfinite(s[k])) continue;
    sss += (s[k] - ms) * (s[k] - ms);
    ssr += (r[k] - mr) * (r[k] - mr);
    srs += (s[k] - ms) * (r[k] - mr);
  }
  if (sss <= 0.0 || ssr <= 0.0) return {};
  return {srs / sss, srs * srs / (sss * ssr)};
}

}  // namespace

const char* phase_name(PhaseKind kind) {
  switch (kind) {
    case PhaseKind::kStanding:
      return "standing";
    case PhaseKind::kStraight:
      return "straight";
    case PhaseKind::kTurning:
      return "turning";
    case PhaseKind::kAccelerating:
      return "accelerating";
  }
  return "unknown";
}

std::vector<PhaseKind> classify_phases(const CommandSeries& cmd, const PhaseThresholds& th) {
  const std::size_t n = cmd.t_s.size();
  std::vector<double> speed(n);
  for (std::size_t k = 0; k < n; ++k) speed[k] = std::hypot(cmd.vx_mps[k], cmd.vy_mps[k]);
  const auto dvx = smoothed_derivative(cmd.t_s, cmd.vx_mps, th.derivative_window_s);
  const auto dvy = smoothed_derivative(cmd.t_s, cmd.vy_mps, th.derivative_window_s);
  const auto dw = smoothed_derivative(cmd.t_s, cmd.wz_radps, th.derivative_window_s);
  std::vector<PhaseKind> out(n, PhaseKind::kStanding);
  for (std::size_t k = 0; k < n; ++k) {
    const double accel = std::hypot(dvx[k], dvy[k]);
    const bool accelerating =
        accel >= th.accel_mps2 || std::abs(dw[k]) >= th.angular_accel_radps2;
    const bool standing = speed[k] < th.standing_speed_mps &&
                          std::abs(cmd.wz_radps[k]) < th.standing_rate_radps;
    if (accelerating) {
      out[k] = PhaseKind::kAccelerating;
    } else if (standing) {
      out[k] = PhaseKind::kStanding;
    } else if (std::abs(cmd.wz_radps[k]) >= th.turning_rate_radps) {
      out[k] = PhaseKind::kTurning;
    } else {
      out[k] = PhaseKind::kStraight;
    }
  }
  return out;
}

std::vector<PhaseSegment> phase_segments(const std::vector<PhaseKind>& phases,
                                         const std::vector<double>& t_s) {
  std::vector<PhaseSegment> out;
  const std::size_t n = std::min(phases.size(), t_s.size());
  std::size_t start = 0;
  for (std::size_t k = 1; k <= n; ++k) {
    if (k == n || phases[k] != phases[start]) {
      PhaseSegment seg;
      seg.kind = phases[start];
      seg.first = start;
      seg.last = k - 1;
      seg.start_s = t_s[start];
      seg.end_s = k < n ? t_s[k] : t_s[n - 1];
      out.push_back(seg);
      start = k;
    }
  }
  return out;
}

MotionSignals motion_signals(const CommandSeries& cmd, const PhaseThresholds& th) {
  const std::size_t n = cmd.t_s.size();
  MotionSignals s;
  s.time_s.resize(n);
  s.distance_m.resize(n);
  s.rotation_rad.resize(n);
  s.speed_mps.resize(n);
  s.yaw_rate_radps = cmd.wz_radps;
  s.velocity_change_mps.resize(n);
  for (std::size_t k = 0; k < n; ++k) s.speed_mps[k] = std::hypot(cmd.vx_mps[k], cmd.vy_mps[k]);
  s.accel_mps2 = smoothed_derivative(cmd.t_s, s.speed_mps, th.derivative_window_s);
  for (std::size_t k = 0; k < n; ++k) {
    s.time_s[k] = cmd.t_s[k] - cmd.t_s[0];
    if (k == 0) continue;
    const double dt = cmd.t_s[k] - cmd.t_s[k - 1];
    s.distance_m[k] = s.distance_m[k - 1] + s.speed_mps[k - 1] * dt;
    s.rotation_rad[k] = s.rotation_rad[k - 1] + cmd.wz_radps[k - 1] * dt;
    s.velocity_change_mps[k] = s.velocity_change_mps[k - 1] + std::abs(s.speed_mps[k] - s.speed_mps[k - 1]);
  }
  return s;
}

Character characterise(const std::vector<double>& residual, const std::vector<double>& predicted,
                       const ChannelInfo& info, const MotionSignals& signals) {
  Character out;
  out.label = "irregular";
  double n = 0.0;
  double sum = 0.0;
  double sum_sq = 0.0;
  for (double r : residual) {
    if (!std::isfinite(r)) continue;
    n += 1.0;
    sum += r;
    sum_sq += r * r;
  }
  if (n < 3.0 || sum_sq <= 0.0) return out;
  // Mostly a constant: the mean carries most of the residual's energy.
  const double mean_share = (sum * sum / n) / sum_sq;
  if (mean_share >= 0.9) {
    out.label = "constant offset";
    out.signal = "constant";
    out.r_squared = mean_share;
    out.slope = sum / n;
    return out;
  }
  // Integrated channels accumulate their error; rate channels see it instantaneously.
  const bool integrated = info.kind != ChannelKind::kYawRate;
  std::vector<double> lag(predicted.size(), 0.0);
  for (std::size_t k = 1; k + 1 < predicted.size(); ++k) {
    const double dt = signals.time_s[k + 1] - signals.time_s[k - 1];
    if (dt > 0.0) lag[k] = -(predicted[k + 1] - predicted[k - 1]) / dt;
  }
  struct Candidate {
    const char* label;
    const char* signal;
    const std::vector<double>* values;
  };
  std::vector<Candidate> candidates;
  if (integrated) {
    candidates = {{"grows with time", "time_s", &signals.time_s},
                  {"grows with distance", "distance_m", &signals.distance_m},
                  {"grows with rotation", "rotation_rad", &signals.rotation_rad},
                  {"grows with acceleration", "velocity_change_mps", &signals.velocity_change_mps},
                  {"lagging", "minus_prediction_rate", &lag}};
  } else {
    candidates = {{"grows with distance", "speed_mps", &signals.speed_mps},
                  {"grows with rotation", "yaw_rate_radps", &signals.yaw_rate_radps},
                  {"grows with acceleration", "accel_mps2", &signals.accel_mps2},
                  {"lagging", "minus_prediction_rate", &lag}};
  }
  double best = 0.0;
  for (const auto& c : candidates) {
    const LineFit fit = fit_line(residual, *c.values);
    if (fit.r_squared > best) {
      best = fit.r_squared;
      out.signal = c.signal;
      out.slope = fit.slope;
      out.r_squared = fit.r_squared;
      out.label = c.label;
    }
  }
  if (best < 0.5) {
    out.label = "irregular";
  }
  return out;
}

std::vector<GrowthWindow> growth_windows(const std::vector<double>& residual,
                                         const std::vector<double>& t_s,
                                         const std::vector<PhaseKind>& phases,
                                         double min_growth_per_s, std::size_t max_windows) {
  std::vector<GrowthWindow> out;
  const std::size_t n = std::min(residual.size(), t_s.size());
  if (n < 2) return out;
  constexpr double kBinS = 1.0;
  struct Bin {
    double start_s, end_s, growth;
    std::array<double, 4> phase_time{};
  };
  std::vector<Bin> bins;
  std::size_t k = 0;
  while (k < n) {
    const double t0 = t_s[k];
    std::size_t j = k;
    Bin bin{t0, t0, 0.0, {}};
    double first = std::numeric_limits<double>::quiet_NaN();
    double last = first;
    while (j < n && t_s[j] < t0 + kBinS) {
      if (std::isfinite(residual[j])) {
        if (!std::isfinite(first)) first = std::abs(residual[j]);
        last = std::abs(residual[j]);
      }
      if (j < phases.size() && j + 1 < n) {
        bin.phase_time[static_cast<std::size_t>(phases[j])] += t_s[j + 1] - t_s[j];
      }
      ++j;
    }
    bin.end_s = j < n ? t_s[j] : t_s[n - 1];
    bin.growth = std::isfinite(first) ? last - first : 0.0;
    bins.push_back(bin);
    k = j;
  }
  double peak = 0.0;
  for (const auto& b : bins) peak = std::max(peak, b.growth / std::max(b.end_s - b.start_s, 1e-9));
  const double threshold = std::max(min_growth_per_s, 0.2 * peak);
  for (std::size_t b = 0; b < bins.size();) {
    const auto rate = [&](std::size_t i) {
      return bins[i].growth / std::max(bins[i].end_s - bins[i].start_s, 1e-9);
    };
    if (rate(b) < threshold || peak <= 0.0) {
      ++b;
      continue;
    }
    GrowthWindow w;
    w.start_s = bins[b].start_s;
    std::array<double, 4> phase_time{};
    while (b < bins.size() && rate(b) >= threshold) {
      w.end_s = bins[b].end_s;
      w.growth += bins[b].growth;
      for (std::size_t p = 0; p < 4; ++p) phase_time[p] += bins[b].phase_time[p];
      ++b;
    }
    w.dominant_phase = static_cast<PhaseKind>(
        std::max_element(phase_time.begin(), phase_time.end()) - phase_time.begin());
    out.push_back(w);
  }
  std::sort(out.begin(), out.end(),
            [](const GrowthWindow& a, const GrowthWindow& b) { return a.growth > b.growth; });
  if (out.size() > max_windows) out.resize(max_windows);
  return out;
}

std::vector<PhaseStat> phase_stats(const std::vector<double>& residual,
                                   const std::vector<PhaseSegment>& segments) {
  std::array<PhaseStat, 4> acc{};
  std::array<double, 4> sum_sq{};
  std::array<double, 4> count{};
  std::array<double, 4> growth{};
  for (std::size_t p = 0; p < 4; ++p) acc[p].kind = static_cast<PhaseKind>(p);
  for (const auto& seg : segments) {
    const auto p = static_cast<std::size_t>(seg.kind);
    acc[p].duration_s += seg.end_s - seg.start_s;
    double first = std::numeric_limits<double>::quiet_NaN();
    double last = first;
    for (std::size_t k = seg.first; k <= seg.last && k < residual.size(); ++k) {
      if (!std::isfinite(residual[k])) continue;
      sum_sq[p] += residual[k] * residual[k];
      count[p] += 1.0;
      if (!std::isfinite(first)) first = residual[k];
      last = residual[k];
    }
    if (std::isfinite(first)) growth[p] += std::abs(last - first);
  }
  std::vector<PhaseStat> out;
  for (std::size_t p = 0; p < 4; ++p) {
    if (acc[p].duration_s <= 0.0) continue;
    acc[p].rms = count[p] > 0.0 ? std::sqrt(sum_sq[p] / count[p]) : 0.0;
    acc[p].growth_per_s = growth[p] / acc[p].duration_s;
    out.push_back(acc[p]);
  }
  return out;
}

}  // namespace swivel::model_gap
