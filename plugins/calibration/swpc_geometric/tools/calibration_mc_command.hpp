// SPDX-License-Identifier: Apache-2.0
#pragma once
// `reproduce calibration-mc`: the paper's Table 3 Monte Carlo as a command-line subcommand,
// ready to be registered under any CLI11 `reproduce` command (swivel-lab's included).

#include <CLI/CLI.hpp>

namespace swivel::calibration {

/// Adds the `calibration-mc` subcommand to `reproduce`. Options: --trials (10000), --seed,
/// --noise (repeatable: none | <pos>mm,<yaw>deg; default: none, 0.1mm,0.05deg and
/// 0.5mm,0.2deg), --progress (force the progress bar when stderr is not a terminal).
/// The subcommand prints the table on stdout and its progress on stderr.
CLI::App* add_calibration_mc_command(CLI::App& reproduce);

}  // namespace swivel::calibration
