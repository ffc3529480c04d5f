// SPDX-License-Identifier: Apache-2.0
#pragma once
// The robot's own motion controller at 1 kHz: it knows only the nominal model. It limits the
// body acceleration of the user's setpoint, then turns the limited twist into wheel and
// steering rate setpoints by the nominal inverse kinematics at the measured steering angles
// (plus the nominal offset), and clamps the steering rates.

#include <array>

#include "swivel/independent/differential_kinematics.hpp"
#include "swivel/independent/run_spec.hpp"
#include "swivel/independent/swpc_kinematics.hpp"

namespace swivel::independent {

struct DriveSetpoints {
  std::array<double, kMaxWheels> wheel_radps{};  ///< docent [0] left, [1] right
  std::array<double, kMaxWheels> steer_radps{};  ///< swpc4
};

class Controller {
 public:
  /// The robot of `spec`: its limits are the true robot's (`spec.truth`).
  explicit Controller(const RunSpec& spec);

  /// One control period of `period_s`: `measured_steer_rad` as the encoders read them.
  DriveSetpoints update(const Twist& setpoint,
                        const std::array<double, kMaxWheels>& measured_steer_rad, double period_s);

  /// The body twist after the acceleration limits.
  [[nodiscard]] const Twist& limited() const { return limited_; }

 private:
  Robot robot_;
  DifferentialGeometry differential_;
  std::array<SwpcModule, 4> modules_;
  double linear_accel_mps2_;
  double angular_accel_radps2_;
  double steer_rate_limit_radps_;
  Twist limited_;
};

}  // namespace swivel::independent
