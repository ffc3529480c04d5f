// swivel-lab gap: the model-gap workflow (DESIGN.md "Model-gap workflow") on a run log and
// the robot's nominal model; writes DIR/report.json, DIR/report.md (with PNG plots) and
// DIR/model_augmented.yaml.

#include <CLI/CLI.hpp>

#include <iomanip>
#include <iostream>
#include <memory>
#include <string>

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
  std::cout << "verdict: " << model_gap::verdict_name(result.verdict) << "\n" << result.summary << "\n";
  for (const auto& e : result.named) {
    for (const auto& [key, value] : e.values) {
      std::cout << "  " << e.name << "." << key << " = " << std::setprecision(6) << value
                << " +- " << std::setprecision(2) << e.sigmas.at(key) << "\n";
    }
  }
  for (const auto& p : result.pose_gaps) {
    std::cout << "  " << model_gap::question_name(p.question) << ": final position error "
              << std::setprecision(4) << p.final_position_m_before << " m -> "
              << p.final_position_m_after << " m, final heading error " << p.final_heading_rad_before
              << " rad -> " << p.final_heading_rad_after << " rad\n";
  }
  std::cout << "report: " << o.out_dir << "/report.md (" << std::setprecision(3) << result.wall_time_s
            << " s)\n";
  return 0;
}

}  // namespace

void add_gap_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<GapCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "gap",
      "Compare a run with its replay by the nominal model, name the missing effect, fit it "
      "and show the gap before and after");
  cmd->add_option("--model", options->model_file, "nominal robot model (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--run", options->run_file, "measured run log (CSV)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", options->out_dir, "report directory (created)")->required();
  cmd->add_option("--holdout", options->gap.holdout_fraction,
                  "share of the run at its end kept for validation")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 0.5));
  cmd->add_option("--min-explained", options->gap.min_explained,
                  "share of the held-out residual above noise an effect must remove to be named")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 1.0));
  cmd->callback([options, &exit_code] { exit_code = run_gap(*options); });
}

}  // namespace swivel::lab
