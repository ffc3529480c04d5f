// SPDX-License-Identifier: Apache-2.0
#pragma once
// The options `swivel-lab gap` and `swivel-lab gap-cross` share: the nominal model, the report
// directory and how the workflow decides (tools/lab/GAP.md).

#include <CLI/CLI.hpp>
#include <string>

#include "swivel/model_gap/workflow.hpp"

namespace swivel::lab {

/// The nominal model, the report directory and the windows: every gap command's.
inline void add_gap_model_options(CLI::App* cmd, std::string& model_file, std::string& out_dir,
                                  model_gap::GapOptions& gap) {
  cmd->add_option("--model", model_file, "nominal robot model (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", out_dir, "report directory (created)")->required();
  cmd->add_option("--window", gap.window_s, "length of the windows compared, s")
      ->capture_default_str()
      ->check(CLI::Range(0.2, 10.0));
}

/// add_gap_model_options() and how the workflow decides: the commands that fit (gap,
/// gap-cross).
inline void add_shared_gap_options(CLI::App* cmd, std::string& model_file, std::string& out_dir,
                                   model_gap::GapOptions& gap) {
  add_gap_model_options(cmd, model_file, out_dir, gap);
  cmd->add_option("--min-sigma", gap.question.min_z_name,
                  "significance (normal deviates) an effect needs to be named")
      ->capture_default_str()
      ->check(CLI::Range(2.0, 20.0));
  cmd->add_option("--calibrate-sigma", gap.question.min_z_calibrate,
                  "significance a parameter of the robot's own model needs to be calibrated "
                  "when nothing is named")
      ->capture_default_str()
      ->check(CLI::Range(2.0, 20.0));
}

}  // namespace swivel::lab
