// SPDX-License-Identifier: Apache-2.0
#pragma once
// What every Swivel executable does with its command line: `--version`, and exit code 2 on a
// usage error (an unknown option, a missing or malformed argument), as POSIX utilities do,
// instead of CLI11's own codes (105-114).

#include <CLI/CLI.hpp>
#include <optional>
#include <string_view>

namespace swivel::cli {

/// The exit code of a usage error.
inline constexpr int kUsageError = 2;

/// Adds `--version` (prints version_line(program)) to `app`. parse() does this; for the
/// binaries that parse in other ways.
void add_version_flag(CLI::App& app, std::string_view program);

/// Adds `--version` and parses. Returns std::nullopt when the program should go on, else the
/// exit code to return from main(): 0 after --help or --version (printed to stdout),
/// kUsageError after a usage error (CLI11's message on stderr), or the code of a
/// CLI::RuntimeError that a subcommand's callback threw to end the program. Other exceptions
/// thrown by callbacks propagate.
[[nodiscard]] std::optional<int> parse(CLI::App& app, int argc, const char* const* argv,
                                       std::string_view program);

/// The exit code for `error`, after printing it as CLI11 does (see parse()).
[[nodiscard]] int exit_code(CLI::App& app, const CLI::ParseError& error);

}  // namespace swivel::cli
