// SPDX-License-Identifier: Apache-2.0
#pragma once
// The model-gap workflow's effect library, by name: setting the true robot's effects from
// "NAME.PARAM=VALUE" and listing what a correct workflow should name for a run.
//
//   gyro_bias.bias_rad_s            gyro reads true rate + bias
//   gyro_scale.scale                gyro reads scale x true rate
//   wheel_radius.left_scale/right_scale (docent), .module_<i>_scale (swpc4)
//   track_width.scale               docent
//   caster_offset.module_<i>_scale  swpc4
//   steering_offset.module_<i>_rad  swpc4: true offset = nominal + rad
//   sensor_latency.delay_s          encoders and gyro report the state of delay_s ago
//   actuator_lag.time_constant_s    wheel and steering rates lag their setpoints
//   steering_lag.time_constant_s    swpc4: steering rates only
//   steering_rate_limit.radps       swpc4: the robot clamps steering rates to this
//   accel_limit.linear_mps2/.angular_radps2   the robot's controller limits the body
//                                   acceleration to these (named when the model lacks them)
//   slip.gain_per_radps2            ground rate = psi_dot - g |psi_dot| psi_ddot

#include <string>
#include <vector>

#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

struct ExpectedParam {
  std::string key;  ///< e.g. "bias_rad_s", "module_2_scale"
  double value = 0.0;
};

/// One library effect with every one of its parameters (identity values included).
struct ExpectedEffect {
  std::string effect;  ///< e.g. "gyro_bias"
  std::vector<ExpectedParam> params;
};

/// The library effects of the true robot that the nominal model does not have, in library
/// order. Effects outside the library are not listed (a correct workflow names none).
std::vector<ExpectedEffect> expected_effects(const RunSpec& spec);

/// Sets one parameter of the true robot, e.g. "gyro_bias.bias_rad_s=0.006", for the robot
/// `spec.robot` already names.
/// @throws std::invalid_argument naming the problem, e.g.
///   "gyro_bias.bias: unknown parameter (expected: bias_rad_s)",
///   "track_width: not an effect of the swpc4 robot (effects: gyro_bias, ...)",
///   "gyro_scale.scale=3: outside [0.5, 2]".
void set_true_effect(RunSpec& spec, const std::string& assignment);

/// Every "NAME.PARAM" set_true_effect accepts for `robot`.
std::vector<std::string> true_effect_keys(Robot robot);

}  // namespace swivel::independent
