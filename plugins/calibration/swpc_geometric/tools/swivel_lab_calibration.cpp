// Stand-alone front end for the calibration reproductions, with the same command path as
// swivel-lab: `swivel-lab-calibration reproduce calibration-mc ...`.
#include <CLI/CLI.hpp>

#include "calibration_mc_command.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Swivel calibration laboratory: reproduce the geometric calibration results"};
  app.require_subcommand(1);
  CLI::App* reproduce = app.add_subcommand("reproduce", "reproduce a paper's results");
  reproduce->require_subcommand(1);
  swivel::calibration::add_calibration_mc_command(*reproduce);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
