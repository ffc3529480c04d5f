#pragma once
// The E/G settings every localization plugin reads alike: `heading_source` from its own
// params, the gyro's scale and bias (eq. (7)) from the robot model's `sensors.gyro`.

#include "swivel/config/param_reader.hpp"
#include "swivel/localization/eg_odometry.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::localization {

/// Reads `heading_source` (gyro | encoders; default gyro) and, when `robot` is given, its
/// gyro calibration. Not real-time safe.
/// @throws ConfigError naming the params key, or the robot model file for a gyro scale that
///         is zero or not finite, or a bias that is not finite.
EgConfig read_eg_config(ParamReader& params, const RobotModel* robot);

}  // namespace swivel::localization
