// SPDX-License-Identifier: Apache-2.0
#pragma once
// The generator's entry point: a run spec in, a measured run log and the nominal model out.

#include <string>

#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

struct GeneratedRun {
  std::string run_csv;             ///< swivel/run_log.hpp
  std::string nominal_model_yaml;  ///< docs/configuration.md "Robot model"
};

/// Simulates `spec` and writes both files. Deterministic: the same spec gives byte-identical
/// output. @throws std::invalid_argument as validate(spec).
GeneratedRun generate(const RunSpec& spec);

}  // namespace swivel::independent
