// SPDX-License-Identifier: Apache-2.0
#pragma once
// The two files a run hands to its users: the run log (swivel/run_log.hpp) and the
// nominal robot model (docs/configuration.md "Robot model"), written here as text.

#include <string>

#include "swivel/independent/run_spec.hpp"
#include "swivel/independent/simulation.hpp"

namespace swivel::independent {

/// The run log CSV of `record`: the fixed comment lines, a line naming the generator and
/// the seed (nothing about the true robot), the header row, one row per sample. Numbers in
/// the shortest form that reads back to the same double; truth cells empty without a frame.
std::string run_log_csv(const RunSpec& spec, const RunRecord& record);

/// The nominal robot model of `spec.robot`, with `limits:` as `spec.model_limits` says and
/// `effects: {}`.
std::string nominal_model_yaml(const RunSpec& spec);

}  // namespace swivel::independent
