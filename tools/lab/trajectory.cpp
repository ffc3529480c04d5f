// SPDX-License-Identifier: Apache-2.0
#include "trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace swivel::lab {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kSpeedMps = 0.3;
constexpr double kYawRateRadps = 0.5;
constexpr double kSquareSideM = 2.5;
constexpr double kSquareSpeedMps = 0.2;
constexpr double kStopAndGoSpeedMps = 0.4;

}  // namespace

const std::vector<std::string>& trajectory_names() {
  static const std::vector<std::string> names = {
      "straight", "arc",    "spin",           "figure8",    "stop-and-go",
      "square",   "strafe", "spin-translate", "calibration"};
  return names;
}

std::optional<TrajectoryKind> parse_trajectory(const std::string& name) {
  const auto& names = trajectory_names();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return std::nullopt;
  return static_cast<TrajectoryKind>(it - names.begin());
}

bool needs_swpc(TrajectoryKind kind) {
  return kind == TrajectoryKind::kStrafe || kind == TrajectoryKind::kSpinTranslate ||
         kind == TrajectoryKind::kCalibration;
}

double Trajectory::default_duration_s(TrajectoryKind kind) {
  switch (kind) {
    case TrajectoryKind::kFigure8: return 2.0 * 2.0 * kPi / kYawRateRadps + 2.0 * kRampS;
    case TrajectoryKind::kStopAndGo: return 4.0 * 5.5;
    case TrajectoryKind::kSquare:
      return 4.0 * (kSquareSideM / kSquareSpeedMps + 0.5 * kPi / kYawRateRadps + 2.0 * kRampS);
    case TrajectoryKind::kSpin: return 15.0;
    default: return 20.0;
  }
}

Trajectory::Trajectory(TrajectoryKind kind, double duration_s)
    : kind_(kind), duration_s_(duration_s) {
  switch (kind) {
    case TrajectoryKind::kFigure8: {
      const double circle_s = 2.0 * kPi / kYawRateRadps;
      segments_ = {{circle_s, {kSpeedMps, 0.0, kYawRateRadps}, false},
                   {circle_s, {kSpeedMps, 0.0, -kYawRateRadps}, false}};
      break;
    }
    case TrajectoryKind::kStopAndGo:
      segments_ = {{4.0, {kStopAndGoSpeedMps, 0.0, 0.0}, true}, {1.5, {}, false}};
      break;
    case TrajectoryKind::kSquare:
      // A ramped segment of length T covers (T - kRampS) at full rate.
      segments_ = {{kSquareSideM / kSquareSpeedMps + kRampS, {kSquareSpeedMps, 0.0, 0.0}, true},
                   {0.5 * kPi / kYawRateRadps + kRampS, {0.0, 0.0, kYawRateRadps}, true}};
      break;
    default: break;
  }
  for (const Segment& s : segments_) period_s_ += s.duration_s;
}

double Trajectory::envelope(double t_s) const {
  const double up = t_s / kRampS;
  const double down = (duration_s_ - t_s) / kRampS;
  return std::clamp(std::min(up, down), 0.0, 1.0);
}

double Trajectory::envelope_integral(double t_s) const {
  // Integral of envelope() from 0 to t_s (for the commanded heading of spin-translate).
  const double r = std::min(kRampS, 0.5 * duration_s_);
  const double rise = std::min(t_s, r);
  double k = rise * rise / (2.0 * kRampS);
  if (t_s > r) k += std::min(t_s, duration_s_ - r) - r;
  if (t_s > duration_s_ - r) {
    const double a = duration_s_ - r;
    const double b = std::min(t_s, duration_s_);
    // envelope = (D - t)/R on [a, b]
    k += ((duration_s_ - a) * (duration_s_ - a) - (duration_s_ - b) * (duration_s_ - b)) /
         (2.0 * kRampS);
  }
  return k;
}

Twist2 Trajectory::at(double t_s) const {
  const double e = envelope(t_s);
  Twist2 t;
  switch (kind_) {
    case TrajectoryKind::kStraight: t = {kSpeedMps, 0.0, 0.0}; break;
    case TrajectoryKind::kArc: t = {kSpeedMps, 0.0, 0.3}; break;
    case TrajectoryKind::kSpin: t = {0.0, 0.0, kYawRateRadps}; break;
    case TrajectoryKind::kStrafe: t = {0.0, 0.2, 0.0}; break;
    case TrajectoryKind::kSpinTranslate: {
      // Constant world-frame velocity along the start heading while the body spins.
      const double w = 0.5 * kYawRateRadps;
      const double yaw = w * envelope_integral(t_s);
      t = {0.2 * std::cos(yaw), -0.2 * std::sin(yaw), w};
      return Twist2{t.vx_mps * e, t.vy_mps * e, t.wz_radps * e};
    }
    case TrajectoryKind::kCalibration: return Twist2{};
    default: {
      double local = std::fmod(t_s, period_s_);
      for (const Segment& s : segments_) {
        if (local < s.duration_s || &s == &segments_.back()) {
          double k = 1.0;
          if (s.ramp) {
            k = std::clamp(std::min(local, s.duration_s - local) / kRampS, 0.0, 1.0);
          }
          t = Twist2{s.twist.vx_mps * k, s.twist.vy_mps * k, s.twist.wz_radps * k};
          break;
        }
        local -= s.duration_s;
      }
      // Ramped segments start and end at rest by themselves.
      if (kind_ == TrajectoryKind::kStopAndGo || kind_ == TrajectoryKind::kSquare) return t;
      break;
    }
  }
  return Twist2{t.vx_mps * e, t.vy_mps * e, t.wz_radps * e};
}

}  // namespace swivel::lab
