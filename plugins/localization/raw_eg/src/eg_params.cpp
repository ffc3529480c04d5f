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

}  // namespace swivel::localization
