// SPDX-License-Identifier: Apache-2.0
// swivel-lab gap-judge: models judged on runs they were not fitted on (tools/lab/GAP.md
// "Across runs"): each run's sensor-to-pose gap under the nominal model and each fitted one
// (e.g. gap-cross's model_pooled.yaml); writes DIR/judge.md and DIR/judge.json.

#include <CLI/CLI.hpp>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "gap_options.hpp"
#include "swivel/model_gap/judge.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::lab {
namespace {

struct GapJudgeOptions {
  std::string model_file;
  std::vector<std::string> fitted_files;
  std::vector<std::string> run_files;
  std::string out_dir;
  model_gap::GapOptions gap;
};

int run_gap_judge(const GapJudgeOptions& o) {
  std::vector<RobotModel> models = {load_robot_model(o.model_file)};
  std::vector<std::string> names = {o.model_file};
  for (const std::string& f : o.fitted_files) {
    models.push_back(load_robot_model(f));
    names.push_back(f);
  }
  std::vector<model_gap::RunData> runs;
  for (const std::string& f : o.run_files) runs.push_back(model_gap::load_run(f));
  const model_gap::JudgeResult r = model_gap::judge_models(
      models, names, runs, o.gap, [](std::size_t done, std::size_t all, const std::string& what) {
        std::cerr << "[" << done << "/" << all << "] " << what << "\n";
      });
  model_gap::write_judge_report(r, o.out_dir);
  std::cout << "median whole-run RMS position gap (ratio to " << names[0] << "):\n";
  for (const model_gap::JudgedGroup& g : r.groups) {
    std::cout << "  " << g.group << " (" << g.runs << " runs):";
    for (std::size_t m = 0; m < names.size(); ++m) {
      std::cout << "  " << names[m] << " " << std::setprecision(3)
                << 1000.0 * g.median_rms_position_m[m] << " mm";
      if (m > 0) std::cout << " (" << g.median_ratio[m] << ")";
    }
    std::cout << "\n";
  }
  std::cout << "runs not used: " << r.skipped.size() << "\nreport: " << o.out_dir << "/judge.md\n";
  return r.runs.empty() ? 1 : 0;
}

}  // namespace

void add_gap_judge_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<GapJudgeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "gap-judge",
      "Judge fitted robot models on runs they were not fitted on: each run's whole-run RMS "
      "position gap under the nominal model (--model, the reference) and each fitted one");
  add_gap_model_options(cmd, o->model_file, o->out_dir, o->gap);
  cmd->add_option("--fitted", o->fitted_files,
                  "a fitted robot model to judge beside it (repeatable; e.g. gap-cross's "
                  "model_pooled.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("runs", o->run_files,
                  "run logs (CSV) of the robot; grouped by the folder above each run's folder")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->callback([o, &exit_code] { exit_code = run_gap_judge(*o); });
}

}  // namespace swivel::lab
