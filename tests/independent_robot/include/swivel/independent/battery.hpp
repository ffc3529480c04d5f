// SPDX-License-Identifier: Apache-2.0
#pragma once
// The battery: named runs with known answers for benchmarking the model-gap workflow.
// Ids read "<robot>/<effect>/<small|large>", "<robot>/clean/<n>",
// "<robot>/pair/<effect>+<effect>" and "<robot>/outside/<name>".

#include <string>
#include <vector>

#include "swivel/independent/library_effects.hpp"
#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

enum class CaseKind {
  kClean,    ///< the true robot is the nominal one
  kSingle,   ///< one library effect
  kPair,     ///< two library effects
  kOutside,  ///< an effect the library has no name for
};

struct BatteryCase {
  std::string id;     ///< e.g. "swpc4/steering_offset/small"
  std::string robot;  ///< "docent" or "swpc4"
  CaseKind kind = CaseKind::kClean;
  std::string description;               ///< one line
  std::vector<ExpectedEffect> expected;  ///< what a correct workflow names; empty: nothing
  RunSpec spec;
};

/// "clean", "single", "pair" or "outside".
std::string case_kind_name(CaseKind kind);

/// Every case, in a fixed order.
const std::vector<BatteryCase>& battery();

/// Eight representative cases: a clean run per robot, docent gyro_bias/large, swpc4
/// steering_offset/large, docent actuator_lag/large, swpc4 accel_limit/large, the docent
/// pair track_width+actuator_lag and swpc4 outside/floor_drift.
std::vector<BatteryCase> battery_subset();

/// The case with this id, or nullptr.
const BatteryCase* find_case(const std::string& id);

}  // namespace swivel::independent
