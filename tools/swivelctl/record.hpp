// SPDX-License-Identifier: Apache-2.0
#pragma once
// `swivelctl record --out RUN.csv [--duration S]`: a running daemon's run samples
// (swivel_run_samples) written as a run log, the file `swivel-lab gap` and the other offline
// tools read.

#include <CLI/CLI.hpp>

namespace swivel::ctl {

/// Adds the `record` subcommand to `app`. It runs from its callback and ends parsing with
/// CLI::RuntimeError carrying its exit code (0 when the recording was written).
void add_record_command(CLI::App& app);

}  // namespace swivel::ctl
