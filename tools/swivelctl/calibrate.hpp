// SPDX-License-Identifier: Apache-2.0
#pragma once
// `swivelctl calibrate start|cancel|status`: the calibration requests of one daemon.

#include <CLI/CLI.hpp>

namespace swivel::ctl {

/// Adds the `calibrate` subcommand to `app`. It runs from its callback and ends parsing
/// with CLI::RuntimeError carrying its exit code (0 when the request succeeded).
void add_calibrate_command(CLI::App& app);

}  // namespace swivel::ctl
