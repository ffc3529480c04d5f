// SPDX-License-Identifier: Apache-2.0
// swivel-lab gap: the model-gap workflow (tools/lab/GAP.md) on a run log and
// the robot's nominal model; writes DIR/report.json, DIR/report.md (with PNG plots) and
// DIR/model_augmented.yaml.

#include <CLI/CLI.hpp>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>

#include "gap_options.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::lab {
namespace {

struct GapCommandOptions {
  std::string model_file;
  std::string run_file;
  std::string out_dir;
  model_gap::GapOptions gap;
};

int run_gap(const GapCommandOptions& o) {
  const RobotModel nominal = load_robot_model(o.model_file);
  const model_gap::RunData run = model_gap::load_run(o.run_file);
  const model_gap::GapResult result = model_gap::analyse_gap(nominal, run, o.gap);
  model_gap::write_report(result, o.out_dir);
  for (const model_gap::QuestionResult* q : {&result.sensor, &result.command}) {
    if (q == &result.command && !result.command_assessed) continue;
    std::cout << model_gap::question_title(q->question) << ": "
              << model_gap::verdict_name(q->verdict) << "\n  " << q->summary << "\n";
    for (const auto* effects : {&q->named, &q->calibrated}) {
      if (effects == &q->calibrated && !effects->empty())
        std::cout << "    calibrated (parameters of the robot's own model, not missing effects):\n";
      for (const auto& e : *effects) {
        const bool partial = e.observable_combinations < e.keys.size();
        for (std::size_t i = 0; i < e.keys.size(); ++i) {
          std::cout << "    " << (e.limits ? "limits." : e.name + ".") << e.keys[i] << " = "
                    << std::setprecision(6) << e.values[i] << " +- " << std::setprecision(2)
                    << (partial ? e.partial_sigmas[i] : e.sigmas[i]) << "\n";
        }
        if (partial) {
          std::cout
              << "    (the run fixes " << e.observable_combinations << " of " << e.keys.size()
              << " combinations of these; the rest stay at the model's values, and each +- is of"
                 " what the run fixes)\n";
        }
      }
    }
  }
  std::cout << "motion capture and gyro timing (nuisances, fitted with the sensor question; never "
               "robot effects):\n";
  for (const std::string& line : model_gap::truth_nuisance_lines(result))
    std::cout << "  " << line << "\n";
  for (const std::string& note : result.notes) std::cout << "note: " << note << "\n";
  for (const auto& p : result.pose_gaps) {
    std::cout << "  " << model_gap::question_title(p.question) << " replay: final position error "
              << std::setprecision(4) << p.final_position_m_before << " m -> "
              << p.final_position_m_after << " m, final heading error "
              << p.final_heading_rad_before << " rad -> " << p.final_heading_rad_after << " rad\n";
  }
  std::cout << "report: " << o.out_dir << "/report.md (" << std::setprecision(3)
            << result.wall_time_s << " s)\n";
  return 0;
}

}  // namespace

void add_gap_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<GapCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "gap",
      "Compare a run with its replay by the nominal model, name the missing effect, fit it "
      "and show the gap before and after");
  cmd->add_option("--run", options->run_file, "measured run log (CSV)")
      ->required()
      ->check(CLI::ExistingFile);
  add_shared_gap_options(cmd, options->model_file, options->out_dir, options->gap);
  cmd->add_flag(
      "--sensor-only", options->gap.sensor_only,
      "decide only the sensor-to-pose question (for runs whose commands were not logged)");
  cmd->callback([options, &exit_code] { exit_code = run_gap(*options); });
}

}  // namespace swivel::lab
