// SPDX-License-Identifier: Apache-2.0
#include "swivel/differential/differential_kinematics.hpp"

#include <algorithm>
#include <cmath>

namespace swivel::differential {
namespace {

// sin(a)/a and (1 - cos(a))/a = 2 sin^2(a/2)/a; the latter form has no cancellation, so
// both are accurate down to a = 0, which only needs its limit.
double sin_over(double a) noexcept { return a == 0.0 ? 1.0 : std::sin(a) / a; }
double one_minus_cos_over(double a) noexcept {
  if (a == 0.0) return 0.0;
  const double s = std::sin(0.5 * a);
  return 2.0 * s * s / a;
}

}  // namespace

WheelRates inverse(const DifferentialParams& p, double vx_mps, double wz_radps) noexcept {
  const double half_track_m = 0.5 * p.track_width_m;
  return WheelRates{(vx_mps - wz_radps * half_track_m) / p.wheel_radius_left_m,
                    (vx_mps + wz_radps * half_track_m) / p.wheel_radius_right_m};
}

Twist2 forward(const DifferentialParams& p, const WheelRates& rates) noexcept {
  const double v_left_mps = p.wheel_radius_left_m * rates.left_radps;
  const double v_right_mps = p.wheel_radius_right_m * rates.right_radps;
  return Twist2{0.5 * (v_right_mps + v_left_mps), 0.0,
                (v_right_mps - v_left_mps) / p.track_width_m};
}

Pose2 forward_increment(const DifferentialParams& p, double dpsi_left_rad,
                        double dpsi_right_rad) noexcept {
  const double d_left_m = p.wheel_radius_left_m * dpsi_left_rad;     // eq. (2)
  const double d_right_m = p.wheel_radius_right_m * dpsi_right_rad;  // eq. (1)
  const double d_m = 0.5 * (d_right_m + d_left_m);                   // eq. (3)
  const double dyaw_rad = (d_right_m - d_left_m) / p.track_width_m;  // encoder heading
  // Both wheels' rates are constant over a step, so the robot moves on a circular arc of
  // length d: its chord in the start frame is d * (sin a / a, (1 - cos a) / a).
  return Pose2{d_m * sin_over(dyaw_rad), d_m * one_minus_cos_over(dyaw_rad), dyaw_rad};
}

double wheel_limit_scale(const DifferentialParams& p, double vx_mps, double wz_radps,
                         double max_wheel_rate_radps) noexcept {
  if (!(max_wheel_rate_radps > 0.0)) return 0.0;
  const WheelRates rates = inverse(p, vx_mps, wz_radps);
  const double fastest_radps = std::max(std::abs(rates.left_radps), std::abs(rates.right_radps));
  if (!(fastest_radps > max_wheel_rate_radps)) return 1.0;
  return max_wheel_rate_radps / fastest_radps;
}

}  // namespace swivel::differential
