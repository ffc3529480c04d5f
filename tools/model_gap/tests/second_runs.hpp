// SPDX-License-Identifier: Apache-2.0
#pragma once
// A run of the second robot generator (tests/second_robot), read back through the project's
// own readers as a user's files would be: the tests of the model-gap workflow on runs it did
// not make.

#include <cstddef>
#include <string>

#include "swivel/model_gap/run_data.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/second/second_robot.hpp"
#include "swivel/second/validation_set.hpp"

namespace swivel::model_gap {

struct SecondRun {
  RobotModel model;  ///< the nominal model the generator writes
  RunData run;
};

/// Generates `spec` and parses its CSV and YAML; `name` labels both in error messages.
SecondRun load_second_run(const second::RunSpec& spec, const std::string& name);

/// A case of a development seed set with one hidden effect, read back, with what it hides.
struct HiddenEffectRun {
  second::ValidationCase spec;
  SecondRun run;
  double truth = 0.0;  ///< the hidden effect's first parameter
};
/// The case `index` of `seeds` with one hidden effect; throws std::logic_error unless it hides
/// `effect` alone (the seed set's cases are not what the test was written for).
HiddenEffectRun hidden_effect_run(const second::SeedRanges& seeds, std::size_t index,
                                  const std::string& effect);

}  // namespace swivel::model_gap
