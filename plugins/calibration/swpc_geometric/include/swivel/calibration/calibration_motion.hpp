// SPDX-License-Identifier: Apache-2.0
#pragma once
// Exact geometric model of the calibration motion of docs/methods.md §1, for tests and the Monte
// Carlo: the robot turns rigidly about the wheel contact point of one locked module while
// the other casters are self-aligned and roll without slip. It has no dynamics (no caster
// transients, no torque control); the simulator covers those.

#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "swivel/calibration/swpc_calibration.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::calibration {

struct CalibrationMotionOptions {
  /// Measured (encoder) steering angles at which each module is locked, one run each.
  std::vector<double> locked_angles_meas_rad = {0.7853981633974483, 2.8797932657906435};
  double rotation_rad = 1.5707963267948966;  ///< per run; positive = counter-clockwise
  double yaw_rate_radps = 0.5;               ///< magnitude
  /// Motion capture and encoders, synchronised; samples run from t = 0 for as long as the
  /// rotation takes, so the last one falls within one period of its end.
  double sample_rate_hz = 100.0;
  Pose2 start_pose;               ///< world pose of the robot at each run's start
  double position_noise_m = 0.0;  ///< motion capture, 1-sigma per coordinate
  double yaw_noise_rad = 0.0;     ///< motion capture, 1-sigma
};

/// Generates every module's locked runs for a robot with true parameters `truth`.
/// Encoders are exact: locked wheel and steering constant; free steering at the
/// self-aligned angle (measured = true - delta); free wheel angle psi = L theta / r, with L
/// the distance from the free contact point to the pivot (via swivel_swpc_kinematics).
/// Only the motion capture gets Gaussian noise, drawn from `rng`.
/// @returns false with `error` set when a free caster cannot self-align (its steering
/// axis within its caster offset of the pivot) or the options are invalid.
bool generate_calibration_motion(std::span<const SwpcModuleParams> truth,
                                 const CalibrationMotionOptions& options, std::mt19937_64& rng,
                                 CalibrationInput& out, std::string& error);

}  // namespace swivel::calibration
