// SPDX-License-Identifier: Apache-2.0
// swivel-lab reproduce calibration-mc: the Table 3 Monte Carlo, whose subcommand lives with
// the calibration library (calibration_mc_command.hpp).

#include <CLI/CLI.hpp>

#include "calibration_mc_command.hpp"

namespace swivel::lab {

void add_reproduce_calibration_mc_command(CLI::App& reproduce, int& /*exit_code*/) {
  // Failures surface as exceptions (bad --noise) that main() reports with a non-zero exit.
  swivel::calibration::add_calibration_mc_command(reproduce);
}

}  // namespace swivel::lab
