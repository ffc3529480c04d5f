// SPDX-License-Identifier: Apache-2.0
#pragma once
// Effects outside the model-gap library, set from "NAME.PARAM=VALUE":
//
//   floor_drift.vx_mps, .vy_mps          the motion-capture frame translates against the floor
//   dropped_counts.interval_s            mean time between bursts of lost encoder counts
//   dropped_counts.min_counts, .max_counts   counts lost per burst (uniform)
//   eccentric_wheel.wheel, .amplitude    wheel (1-based) whose radius is r (1 + a cos psi)
//   gyro_drift.rad_s                     gyro bias drifts linearly from -x to +x over the run

#include <string>
#include <vector>

#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

/// Sets one parameter of an outside effect.
/// @throws std::invalid_argument naming the problem, as set_true_effect.
void set_outside_effect(RunSpec& spec, const std::string& assignment);

/// Every "NAME.PARAM" set_outside_effect accepts.
std::vector<std::string> outside_effect_keys();

/// Short names of the outside effects a spec has, e.g. {"floor_drift"}.
std::vector<std::string> active_outside_effects(const OutsideEffects& outside);

}  // namespace swivel::independent
