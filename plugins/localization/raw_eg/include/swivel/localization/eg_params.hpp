// SPDX-License-Identifier: Apache-2.0
#pragma once
// The E/G settings every localization plugin reads alike: `heading_source` from its own
// params, the gyro's scale and bias (eq. (7)) from the robot model's `sensors.gyro`.

#include "swivel/config/param_reader.hpp"
#include "swivel/localization/eg_covariance.hpp"
#include "swivel/localization/eg_odometry.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::localization {

/// Reads `heading_source` (gyro | encoders; default gyro) and, when `robot` is given, its
/// gyro calibration. Not real-time safe.
/// @throws ConfigError naming the params key, or the robot model file for a gyro scale that
///         is zero or not finite, or a bias that is not finite.
EgConfig read_eg_config(ParamReader& params, const RobotModel* robot);

/// Reads the E/G noise model (eg_covariance.hpp), every key optional:
///   along_track_noise_m_per_sqrt_m (0.01), cross_track_noise_m_per_sqrt_m (0.01),
///   rotation_noise_rad_per_sqrt_rad (0.05), yaw_noise_rad_per_sqrt_m (0.01),
///   gyro_noise_radps (the robot model's sensors.gyro.noise_rad_s over its scale; 0 without
///   a model), gyro_bias_sigma_radps (0: the model's bias is the calibrated one),
///   bias_random_walk_radps_per_sqrt_s (1e-5).
/// Not real-time safe. @throws ConfigError naming the key.
EgNoise read_eg_noise(ParamReader& params, const RobotModel* robot);

}  // namespace swivel::localization
