// SPDX-License-Identifier: Apache-2.0
#include "square_follower.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace swivel::lab {
namespace {

double wrap(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

double step_towards(double from, double to, double max_step) {
  return from + std::clamp(to - from, -max_step, max_step);
}

}  // namespace

SquareFollower::SquareFollower(const Pose2& start, double side_m, int laps, bool counter_clockwise,
                               const SquareFollowerLimits& limits)
    : limits_(limits) {
  const double turn = counter_clockwise ? 0.5 * std::numbers::pi : -0.5 * std::numbers::pi;
  Pose2 at = start;
  corners_.push_back(at);
  for (int k = 0; k < 4 * laps; ++k) {
    Pose2 next = at;
    next.x_m += side_m * std::cos(at.yaw_rad);
    next.y_m += side_m * std::sin(at.yaw_rad);
    legs_.push_back({false, at, next});
    at = next;
    Pose2 turned = at;
    turned.yaw_rad = at.yaw_rad + turn;
    legs_.push_back({true, at, turned});
    at = turned;
    corners_.push_back(at);
  }
}

Twist2 SquareFollower::limit(const Twist2& wanted, double dt_s) {
  Twist2 t;
  t.vx_mps = step_towards(last_.vx_mps, wanted.vx_mps, limits_.accel_mps2 * dt_s);
  t.vy_mps = step_towards(last_.vy_mps, wanted.vy_mps, limits_.accel_mps2 * dt_s);
  t.wz_radps = step_towards(last_.wz_radps, wanted.wz_radps, limits_.yaw_accel_radps2 * dt_s);
  last_ = t;
  return t;
}

Twist2 SquareFollower::update(const Pose2& odom, double dt_s) {
  while (leg_ < legs_.size()) {
    const Leg& leg = legs_[leg_];
    if (leg.turn) {
      const double err = wrap(leg.to.yaw_rad - odom.yaw_rad);
      if (std::abs(err) < limits_.heading_tolerance_rad && std::abs(last_.wz_radps) < 0.02) {
        ++leg_;
        continue;
      }
      // Slow down in time: w <= sqrt(2 a |err|), and a proportional tail near the end.
      const double cap = std::min(limits_.yaw_rate_radps,
                                  std::sqrt(2.0 * limits_.yaw_accel_radps2 * std::abs(err)));
      const double w = std::clamp(limits_.heading_gain_per_s * err, -cap, cap);
      return limit({0.0, 0.0, w}, dt_s);
    }
    const double dx = std::cos(leg.from.yaw_rad);
    const double dy = std::sin(leg.from.yaw_rad);
    const double ex = leg.to.x_m - odom.x_m;
    const double ey = leg.to.y_m - odom.y_m;
    const double remaining = ex * dx + ey * dy;
    const double cross = -ex * dy + ey * dx;  // left of the line is positive
    if (remaining < limits_.position_tolerance_m && std::hypot(last_.vx_mps, last_.vy_mps) < 0.01) {
      ++leg_;
      continue;
    }
    const double cap =
        std::min(limits_.speed_mps, std::sqrt(2.0 * limits_.accel_mps2 * std::max(0.0, remaining)));
    const double along = std::clamp(2.0 * remaining, -cap, cap);
    const double lateral = limits_.cross_track_gain_per_s * cross;
    // World-frame velocity along the line plus the correction, into the robot frame.
    const double vx_w = along * dx - lateral * dy;
    const double vy_w = along * dy + lateral * dx;
    const double c = std::cos(odom.yaw_rad);
    const double s = std::sin(odom.yaw_rad);
    const double w = limits_.heading_gain_per_s * wrap(leg.from.yaw_rad - odom.yaw_rad);
    return limit({c * vx_w + s * vy_w, -s * vx_w + c * vy_w, w}, dt_s);
  }
  return limit({}, dt_s);
}

}  // namespace swivel::lab
