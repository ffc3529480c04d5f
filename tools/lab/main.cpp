// SPDX-License-Identifier: Apache-2.0
// swivel-lab: the offline tools. Subcommands register themselves through commands.inc.

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "swivel/cli/command_line.hpp"

#define SWIVEL_LAB_COMMAND(name) void add_##name##_command(CLI::App& app, int& exit_code);
namespace swivel::lab {
#include "commands.inc"
}  // namespace swivel::lab
#undef SWIVEL_LAB_COMMAND

// The tool behind main(), which reports what escapes its set-up.
static int lab_main(int argc, char** argv) {
  CLI::App app{"swivel-lab: offline simulation, calibration and model analysis for Swivel robots"};
  app.require_subcommand(1);
  int exit_code = 0;
#define SWIVEL_LAB_COMMAND(name) swivel::lab::add_##name##_command(app, exit_code);
#include "commands.inc"
#undef SWIVEL_LAB_COMMAND
  try {
    // The subcommands run from their callbacks, inside parse().
    if (const auto exit = swivel::cli::parse(app, argc, argv, "swivel-lab")) return *exit;
  } catch (const std::exception& e) {
    std::string where = "swivel-lab";
    for (const CLI::App* sub : app.get_subcommands()) where += " " + sub->get_name();
    std::cerr << where << ": error: " << e.what() << '\n';
    return 1;
  }
  return exit_code;
}

int main(int argc, char** argv) {
  try {
    return lab_main(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "swivel-lab: error: " << e.what() << '\n';
  } catch (...) {
    std::cerr << "swivel-lab: error: an exception that is not a std::exception\n";
  }
  return 1;
}
