// SPDX-License-Identifier: Apache-2.0
// swivel-lab gap-cross: cross-run evidence for the model-gap workflow (tools/lab/GAP.md
// "Across runs"): fit on each run of a robot, validate on the others, and check that the named
// values agree across runs; writes DIR/cross_run.md and DIR/cross_run.json.

#include <CLI/CLI.hpp>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "gap_options.hpp"
#include "swivel/model_gap/cross_run.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::lab {
namespace {

struct GapCrossOptions {
  std::string model_file;
  std::vector<std::string> run_files;
  std::string out_dir;
  model_gap::GapOptions gap;
};

int run_gap_cross(const GapCrossOptions& o) {
  const RobotModel nominal = load_robot_model(o.model_file);
  std::vector<model_gap::RunData> runs;
  for (const std::string& f : o.run_files) runs.push_back(model_gap::load_run(f));
  const model_gap::CrossRunResult r = model_gap::cross_validate(
      nominal, runs, o.gap, [](std::size_t done, std::size_t all, const std::string& what) {
        std::cerr << "[" << done << "/" << all << "] " << what << "\n";
      });
  model_gap::write_cross_run_report(r, nominal, o.out_dir);
  std::cout << std::setprecision(4);
  for (const model_gap::FitRun& f : r.fits) {
    std::cout << f.run << ": " << model_gap::verdict_name(f.verdict);
    for (const model_gap::FittedEffect& e : f.named) {
      for (std::size_t i = 0; i < e.keys.size(); ++i)
        std::cout << "  " << e.name << "." << e.keys[i] << " = " << e.values[i];
    }
    for (const model_gap::FittedEffect& e : f.calibrated) {
      for (std::size_t i = 0; i < e.keys.size(); ++i)
        std::cout << "  calibrated " << e.name << "." << e.keys[i] << " = " << e.values[i];
    }
    std::cout << "\n";
  }
  for (const model_gap::ParameterAgreement& a : r.agreement) {
    std::cout << a.name << ": " << a.values.size() << " runs, weighted mean "
              << std::setprecision(6) << a.weighted_mean << " +- " << std::setprecision(2)
              << a.sigma_of_mean << ", chi^2 " << std::setprecision(4) << a.chi_square << " / "
              << a.dof << ", " << std::setprecision(3) << 100.0 * a.within_2_sigma
              << " % within 2 sigma of the others\n";
  }
  std::cout << "median ratio of the held-out RMS position gap (fitted / nominal) over " << r.pairs
            << " pairs within sessions: " << std::setprecision(3) << r.median_ratio << "\n"
            << "  over the " << r.pairs_named
            << " pairs whose fit run named or calibrated something: " << r.median_ratio_named
            << " (" << 1000.0 * r.median_nominal_rms_m << " mm -> "
            << 1000.0 * r.median_fitted_rms_m << " mm, medians)\n"
            << "sensor verdicts: " << r.named << " named, " << r.no_gap << " no significant gap ("
            << r.calibrated << " of them calibrated), " << r.unexplained << " unexplained, of "
            << r.fits.size() << "; runs not used: " << r.skipped.size() << "\n"
            << "report: " << o.out_dir << "/cross_run.md\n";
  return 0;
}

}  // namespace

void add_gap_cross_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<GapCrossOptions>();
  CLI::App* cmd = app.add_subcommand(
      "gap-cross",
      "Fit the sensor-to-pose question on each run of one robot and judge the fitted model on "
      "its other runs; check that the named values agree across runs");
  add_shared_gap_options(cmd, options->model_file, options->out_dir, options->gap);
  cmd->add_option("runs", options->run_files,
                  "run logs (CSV) of one robot, at least two; a run is judged on the others in "
                  "its folder (its session)")
      ->required()
      ->check(CLI::ExistingFile)
      ->expected(2, -1);
  cmd->callback([options, &exit_code] { exit_code = run_gap_cross(*options); });
}

}  // namespace swivel::lab
