// SPDX-License-Identifier: Apache-2.0
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

}  // namespace

const char* phase_name(PhaseKind kind) {
  switch (kind) {
    case PhaseKind::kStanding: return "standing";
    case PhaseKind::kStraight: return "straight";
    case PhaseKind::kTurning: return "turning";
    case PhaseKind::kAccelerating: return "accelerating";
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
    const bool accelerating = accel >= th.accel_mps2 || std::abs(dw[k]) >= th.angular_accel_radps2;
    const bool standing =
        speed[k] < th.standing_speed_mps && std::abs(cmd.wz_radps[k]) < th.standing_rate_radps;
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

}  // namespace swivel::model_gap
