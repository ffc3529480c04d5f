// SPDX-License-Identifier: Apache-2.0
#pragma once
// Judging fitted models on runs they were not fitted on (tools/lab/GAP.md "Across runs"):
// every run's sensor-to-pose gap under each model, with the run's own motion-capture
// nuisances fitted for that model (held_out_gap), and the medians per group of runs (the
// folder above a run's session folder, e.g. square/ and ivanjko/) and over all.

#include <cstddef>
#include <string>
#include <vector>

#include "swivel/model_gap/cross_run.hpp"

namespace swivel::model_gap {

struct JudgedRun {
  std::string run;
  std::string group;                   ///< the folder above the run's session folder
  std::vector<double> rms_position_m;  ///< per model
};

/// The medians of one group of runs (or of all: group "all").
struct JudgedGroup {
  std::string group;
  std::size_t runs = 0;
  std::vector<double> median_rms_position_m;  ///< per model
  std::vector<double> median_ratio;           ///< per model: its gap over the first model's
};

struct JudgeResult {
  std::vector<std::string> models;  ///< files, the first the reference
  std::vector<JudgedRun> runs;
  std::vector<JudgedGroup> groups;   ///< each group, then "all"
  std::vector<std::string> skipped;  ///< "run: reason"
};

/// Each run under each model (`names` their files, the first the reference).
JudgeResult judge_models(const std::vector<RobotModel>& models,
                         const std::vector<std::string>& names, const std::vector<RunData>& runs,
                         const GapOptions& options, const CrossRunProgress& progress = {});

/// Writes DIR/judge.md and DIR/judge.json. Creates DIR.
/// @throws std::runtime_error when a file cannot be written.
void write_judge_report(const JudgeResult& result, const std::string& dir);

}  // namespace swivel::model_gap
