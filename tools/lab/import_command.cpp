// SPDX-License-Identifier: Apache-2.0
// swivel-lab import: another lab's CSV into a Swivel run log through a mapping file
// (tools/lab/IMPORT.md), so that the model-gap workflow and calibration read it.

#include <CLI/CLI.hpp>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>

#include "swivel/robot_model_io.hpp"
#include "swivel/run_import/run_import.hpp"

namespace swivel::lab {
namespace {

struct ImportOptions {
  std::string map_file;
  std::string model_file;
  std::string out_file;
  std::string in_file;
};

int run_import(const ImportOptions& o) {
  const run_import::ImportMap map = run_import::load_import_map(o.map_file);
  if (!o.model_file.empty()) {
    run_import::check_map_matches_model(map, load_robot_model(o.model_file));
  }
  const run_import::ImportSummary s = run_import::import_file(map, o.in_file, o.out_file);
  std::cout << o.in_file << " -> " << o.out_file << ": " << s.rows << " rows, t "
            << std::setprecision(6) << s.first_t_s << " .. " << s.last_t_s << " s; truth in "
            << s.truth_rows << ", gyro in " << s.gyro_rows << ", commands in " << s.command_rows
            << " rows";
  if (s.gaps > 0) std::cout << "; " << s.gaps << " gaps of a row or more in the time column";
  std::cout << "\n";
  return 0;
}

}  // namespace

void add_import_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<ImportOptions>();
  CLI::App* cmd = app.add_subcommand(
      "import",
      "Convert another lab's CSV into a Swivel run log, as a mapping file (tools/lab/IMPORT.md) "
      "describes its columns, units and signs");
  cmd->add_option("--map", options->map_file, "import map (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", options->out_file, "run log to write (CSV, overwritten)")->required();
  cmd->add_option("--model", options->model_file,
                  "robot model the run will be analysed with: refuse a map whose robot name, "
                  "drivetrain or module count differs")
      ->check(CLI::ExistingFile);
  cmd->add_option("input", options->in_file, "the lab's CSV file")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->callback([options, &exit_code] { exit_code = run_import(*options); });
}

}  // namespace swivel::lab
