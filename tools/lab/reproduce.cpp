// SPDX-License-Identifier: Apache-2.0
// swivel-lab reproduce: the group of paper reproductions (docs/methods.md). Each reproduction lives
// in its own file and is listed in reproduce.inc, so that adding one touches one line here.

#include <CLI/CLI.hpp>

#define SWIVEL_LAB_REPRODUCE(name) \
  void add_reproduce_##name##_command(CLI::App& reproduce, int& exit_code);
namespace swivel::lab {
#include "reproduce.inc"
}  // namespace swivel::lab
#undef SWIVEL_LAB_REPRODUCE

namespace swivel::lab {

void add_reproduce_command(CLI::App& app, int& exit_code) {
  CLI::App* reproduce = app.add_subcommand(
      "reproduce", "Reproduce a paper's experiments in simulation and compare with its tables");
  reproduce->require_subcommand(1);
#define SWIVEL_LAB_REPRODUCE(name) add_reproduce_##name##_command(*reproduce, exit_code);
#include "reproduce.inc"
#undef SWIVEL_LAB_REPRODUCE
}

}  // namespace swivel::lab
