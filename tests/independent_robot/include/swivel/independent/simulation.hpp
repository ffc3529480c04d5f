// SPDX-License-Identifier: Apache-2.0
#pragma once
// The true robot, its controller and its sensors, run over a tour: one row per log sample,
// every value taken at that row's own time.

#include <array>
#include <vector>

#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

/// One row of the run log, plus the noise-free truth behind it (for checks).
struct RunRow {
  double t_s = 0.0;
  Twist cmd;                                   ///< the user's setpoint at t (before limits)
  std::array<double, kMaxWheels> wheel_rad{};  ///< encoders, cumulative, quantized
  std::array<double, kMaxWheels> steer_rad{};  ///< swpc4: true - offset, quantized
  double gyro_wz_radps = 0.0;
  bool has_truth = false;  ///< a motion-capture frame fell in (previous row's t, t]
  Pose truth;              ///< motion capture: pose at t, floor drift and noise, yaw wrapped
  Pose true_pose;          ///< the robot's pose at t on the floor, yaw unwrapped
  Twist true_twist;        ///< the robot's body twist at t
};

struct RunRecord {
  Robot robot = Robot::kDocent;
  std::vector<RunRow> rows;
};

/// Runs `spec`. Deterministic: the same spec gives the same record.
/// @throws std::invalid_argument as validate(spec).
RunRecord simulate(const RunSpec& spec);

}  // namespace swivel::independent
