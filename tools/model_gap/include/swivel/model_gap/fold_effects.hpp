// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the workflow names becomes what the robot runs on: every named effect that has a
// parameter in the robot model itself is folded into that parameter, so that the daemon's
// drivetrain and localization (which read `differential:` / `swpc:` and `sensors:`, never
// `effects:`) use it. Exactly as sim::resolve_plant() applies the effects
// (plugins/hardware/sim/include/swivel/sim/effects.hpp):
//
//   effect           folded into
//   gyro_bias        sensors.gyro.bias_rad_s += bias_rad_s
//   gyro_scale       sensors.gyro.scale *= scale
//   wheel_radius     differential.wheel_radius_left_m *= left_scale, _right_m *= right_scale;
//                    swpc: modules[i].wheel_radius_m *= module_<i+1>_scale
//   track_width      differential.track_width_m *= scale
//   caster_offset    swpc: modules[i].caster_offset_m *= module_<i+1>_scale
//   steering_offset  swpc: modules[i].steering_offset_rad += module_<i+1>_rad (true steering
//                    = measured + offset, in the model as in the world)
//   module_layout    swpc: modules[i].x_m *= longitudinal_scale, modules[i].y_m *=
//                    lateral_scale (every module; one folded line per position changed)
//
// so that resolve_plant() of the folded model equals resolve_plant() of the model with the
// effects. The rest stays in `effects:`, for the simulator, each with the reason the daemon
// cannot use it: slip, actuator_lag, steering_lag (the drivetrains command rates and
// integrate the encoders as rolling without slip; nothing in the robot model describes the
// actuators' response), sensor_latency (the robot model has no latency parameter and the
// localizations integrate each reading as of the cycle it arrives in), track_scrub (the robot
// model has one track width for every kind of turn).

#include <string>
#include <vector>

#include "swivel/robot_model.hpp"

namespace swivel::model_gap {

struct FoldResult {
  /// The robot's parameters with the foldable effects in them; `effects:` holds the rest.
  RobotModel model;
  /// One line per folded effect, e.g. "gyro_bias.bias_rad_s = 0.004 -> sensors.gyro.bias_rad_s
  /// 0 -> 0.004".
  std::vector<std::string> folded;
  /// One line per effect kept in `effects:`, with the reason, e.g. "slip: ...".
  std::vector<std::string> kept;
};

/// Whether effect `name` has a parameter in a robot model of drivetrain `kind` (the table
/// above): what a run can calibrate rather than name.
bool folds_into_robot_model(const std::string& name, DrivetrainKind kind);

/// Folds `model.effects` into the model's own parameters where it has them.
/// @throws std::invalid_argument as sim::validate_effects for an invalid effect.
FoldResult fold_effects(const RobotModel& model);

/// Writes fold_effects(model).model to `path` as YAML the daemon loads, under comment lines:
/// `title`, then what was folded where and what stayed in `effects:` and why.
/// @throws std::runtime_error when the file cannot be written.
void write_folded_model(const RobotModel& model, const std::string& title, const std::string& path);

}  // namespace swivel::model_gap
