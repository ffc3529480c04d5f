// SPDX-License-Identifier: Apache-2.0
#pragma once
// Range checks of a spec's effects, shared by validate() and the NAME.PARAM=VALUE setters so
// that both report the same names and ranges.

#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

/// @throws std::invalid_argument "truth: gyro_scale.scale=3: outside [0.5, 2]" and the like,
///   or for an effect set on a robot that does not have it.
void check_true_effects(const RunSpec& spec);

/// @throws std::invalid_argument "outside: eccentric_wheel.wheel=3: outside [0, 2]" and the like.
void check_outside_effects(const RunSpec& spec);

}  // namespace swivel::independent
