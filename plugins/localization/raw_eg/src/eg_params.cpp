// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/eg_params.hpp"

#include <cmath>

#include "swivel/config/config_error.hpp"

namespace swivel::localization {

EgConfig read_eg_config(ParamReader& params, const RobotModel* robot) {
  EgConfig config;
  config.heading_source = params.choice_or("heading_source", "gyro", {"gyro", "encoders"}) == "gyro"
                              ? HeadingSource::kGyro
                              : HeadingSource::kEncoders;
  if (robot != nullptr) {
    const GyroParams& gyro = robot->sensors.gyro;
    if (!std::isfinite(gyro.scale) || gyro.scale == 0.0 || !std::isfinite(gyro.bias_rad_s)) {
      throw ConfigError(robot->source_file +
                        ": sensors.gyro: expected a finite non-zero scale and a finite bias");
    }
    config.gyro_scale = gyro.scale;
    config.gyro_bias_radps = gyro.bias_rad_s;
  }
  return config;
}

EgNoise read_eg_noise(ParamReader& params, const RobotModel* robot) {
  EgNoise n;
  n.along_track_m_per_sqrt_m =
      params.number_or("along_track_noise_m_per_sqrt_m", n.along_track_m_per_sqrt_m, 0.0, 10.0);
  n.cross_track_m_per_sqrt_m =
      params.number_or("cross_track_noise_m_per_sqrt_m", n.cross_track_m_per_sqrt_m, 0.0, 10.0);
  n.rotation_rad_per_sqrt_rad =
      params.number_or("rotation_noise_rad_per_sqrt_rad", n.rotation_rad_per_sqrt_rad, 0.0, 10.0);
  n.yaw_rad_per_sqrt_m =
      params.number_or("yaw_noise_rad_per_sqrt_m", n.yaw_rad_per_sqrt_m, 0.0, 10.0);
  double gyro_noise = 0.0;
  if (robot != nullptr) {
    const GyroParams& gyro = robot->sensors.gyro;
    // read_eg_config() rejects a zero or non-finite scale with the model's file named.
    if (std::isfinite(gyro.scale) && gyro.scale != 0.0 && std::isfinite(gyro.noise_rad_s)) {
      gyro_noise = std::abs(gyro.noise_rad_s / gyro.scale);
    }
  }
  n.gyro_noise_radps = params.number_or("gyro_noise_radps", gyro_noise, 0.0, 10.0);
  n.gyro_bias_sigma_radps = params.number_or("gyro_bias_sigma_radps", 0.0, 0.0, 10.0);
  n.bias_walk_radps_per_sqrt_s =
      params.number_or("bias_random_walk_radps_per_sqrt_s", 1e-5, 0.0, 1.0);
  return n;
}

}  // namespace swivel::localization
