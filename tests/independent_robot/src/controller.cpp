// SPDX-License-Identifier: Apache-2.0
#include "controller.hpp"

#include <algorithm>

#include "swivel/independent/nominal_robots.hpp"

namespace swivel::independent {
namespace {

double approach(double current, double target, double max_step) {
  return current + std::clamp(target - current, -max_step, max_step);
}

}  // namespace

Controller::Controller(const RunSpec& spec)
    : robot_(spec.robot),
      differential_(docent_nominal()),
      modules_(swpc4_nominal()),
      linear_accel_mps2_(spec.truth.linear_accel_limit_mps2),
      angular_accel_radps2_(spec.truth.angular_accel_limit_radps2),
      steer_rate_limit_radps_(spec.truth.steering_rate_limit_radps) {}

DriveSetpoints Controller::update(const Twist& setpoint,
                                  const std::array<double, kMaxWheels>& measured_steer_rad,
                                  double period_s) {
  // Each axis on its own: x, y at the linear limit, yaw at the angular one.
  limited_.vx_mps = approach(limited_.vx_mps, setpoint.vx_mps, linear_accel_mps2_ * period_s);
  limited_.vy_mps = approach(limited_.vy_mps, setpoint.vy_mps, linear_accel_mps2_ * period_s);
  limited_.wz_radps =
      approach(limited_.wz_radps, setpoint.wz_radps, angular_accel_radps2_ * period_s);

  DriveSetpoints out;
  if (robot_ == Robot::kDocent) {
    const WheelPairRates r =
        differential_inverse(differential_, limited_.vx_mps, limited_.wz_radps);
    out.wheel_radps[0] = r.left_radps;
    out.wheel_radps[1] = r.right_radps;
    return out;
  }
  for (std::size_t i = 0; i < modules_.size(); ++i) {
    const SwpcModule& m = modules_[i];
    const ModuleRates r = swpc_inverse(m, measured_steer_rad[i] + m.steering_offset_rad, limited_);
    out.wheel_radps[i] = r.wheel_radps;
    out.steer_radps[i] =
        std::clamp(r.steer_radps, -steer_rate_limit_radps_, steer_rate_limit_radps_);
  }
  return out;
}

}  // namespace swivel::independent
