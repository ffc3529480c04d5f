// SPDX-License-Identifier: Apache-2.0
#pragma once
// The library of named effects (README "Configuration reference: robot model", `effects:`): small,
// documented extensions of a robot model that the simulated world applies on top of the model's
// parameters. This file and effects.cpp are the only place that defines them: their names,
// parameters, identity values, ranges and how each alters the world. The model-gap
// workflow fits the same effects, so what it names is exactly what the simulator does.
//
//   effect          parameters (identity)             what the world does
//   gyro_bias       bias_rad_s (0)                    gyro bias += bias_rad_s
//   gyro_scale      scale (1)                         gyro scale *= scale
//   wheel_radius    left_scale, right_scale (1)       true wheel radius *= scale
//                   (swpc: module_<i>_scale, i = 1..N)
//   track_width     scale (1)          differential   true track width *= scale
//   track_scrub     spin_scale (1)     differential   the effective track depends on how the
//                                                     robot turns (tyre scrub): track *
//                                                     (1 + (spin_scale - 1) s), s the share of
//                                                     turning in the wheel rates (spin_share)
//   caster_offset   module_<i>_scale (1)   swpc       true caster offset *= scale
//   steering_offset module_<i>_rad (0)     swpc       true steering offset += rad, so the
//                                                     encoder reads true - offset
//   module_layout   lateral_scale,         swpc       true module positions: every steering
//                   longitudinal_scale (1)            axis's y *= lateral_scale and x *=
//                                                     longitudinal_scale, about the robot
//                                                     frame's origin (modules sit wider
//                                                     apart or further fore and aft)
//   slip            gain_per_radps2 (0)               longitudinal slip: the contact point
//                                                     rolls r (psi_dot - g |psi_dot| psi_ddot)
//                                                     (less than the wheel turns while it
//                                                     speeds up, more while it slows down)
//   actuator_lag    time_constant_s (0)               wheel and steering rates follow their
//                                                     setpoints through a first-order lag
//   steering_lag    time_constant_s (0)    swpc       the steering drives' own response: their
//                                                     rates follow through this lag instead
//   sensor_latency  delay_s (0)                       encoders and gyro report the state of
//                                                     delay_s ago; motion capture does not
//
// The robot model's `limits:` belong to the robot's own motion controller, not to the world:
// PlantParams carries them for whoever plays that controller (OpenLoopController and the
// TwistLimiter of swivel::motion).
//
// Parameters left out of an effect take their identity value. Not real-time safe
// (allocates); the world resolves effects once at construction.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::sim {

/// One parameter of an effect.
struct EffectParamInfo {
  std::string key;        ///< e.g. "bias_rad_s", "module_2_scale"
  double identity = 0.0;  ///< value at which the parameter changes nothing
  double min = 0.0;       ///< accepted range, inclusive
  double max = 0.0;
  std::string description;
};

/// One named effect with its parameters expanded for a given robot.
struct EffectInfo {
  std::string name;
  std::string description;
  std::vector<EffectParamInfo> params;
};

/// Every effect of the library that applies to `model`'s drivetrain, with per-module
/// parameters expanded for its module count.
std::vector<EffectInfo> effect_library(const RobotModel& model);

/// The effect named `name` in `library`, or nullptr.
const EffectInfo* find_effect(const std::vector<EffectInfo>& library, const std::string& name);

/// Checks model.effects against the library.
/// @throws std::invalid_argument naming the effect and parameter, e.g.
///   "effects.track_width: not available for a swpc robot (available: gyro_bias, ...)" or
///   "effects.gyro_bias.bias: unknown parameter (expected: bias_rad_s)" or
///   "effects.gyro_scale.scale: 3 is outside [0.5, 2]".
void validate_effects(const RobotModel& model);

/// Sets one effect parameter from "NAME.PARAM=VALUE" (the `--effect` option), adding the
/// effect when absent. @throws std::invalid_argument for bad syntax or as validate_effects.
void set_effect(RobotModel& model, const std::string& assignment);

/// The physical world of a robot: the model's parameters with its effects folded in.
struct PlantParams {
  DrivetrainKind drivetrain = DrivetrainKind::kDifferential;
  DifferentialParams differential;
  std::size_t module_count = 2;                         ///< 2 for differential
  std::array<SwpcModuleParams, kMaxModules> modules{};  ///< first module_count used (swpc)
  SensorParams sensors;                                 ///< gyro scale and bias included
  double slip_gain_per_radps2 = 0.0;
  double actuator_time_constant_s = 0.0;  ///< wheels (and steering without steering_lag)
  double steering_time_constant_s = 0.0;  ///< steering drives
  double sensor_delay_s = 0.0;
  /// track_scrub: the effective track turning on the spot over that on straight paths.
  double track_spin_scale = 1.0;
  MotionLimits limits;  ///< the model's `limits:`
};

/// How much of a differential robot's wheel motion is turning: |r - l| / (|r + l| + |r - l|)
/// of the wheel rates (or increments) l, r; 1 turning on the spot, 0 straight, 0 at rest.
double spin_share(double left, double right);

/// The differential geometry that moves the robot for wheel rates (or increments) l, r: the
/// plant's, with the track of its track_scrub for that turn.
DifferentialParams effective_differential(const PlantParams& plant, double left, double right);

/// Folds `model.effects` into the model's parameters.
/// @throws std::invalid_argument as validate_effects, or for a model without 2..kMaxModules
///         modules (swpc).
PlantParams resolve_plant(const RobotModel& model);

}  // namespace swivel::sim
