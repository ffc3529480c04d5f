// SPDX-License-Identifier: Apache-2.0
#include "swivel/cli/command_line.hpp"

#include <string>

#include "swivel/version.hpp"

namespace swivel::cli {

void add_version_flag(CLI::App& app, std::string_view program) {
  app.set_version_flag("--version", version_line(program), "print the version and exit");
}

int exit_code(CLI::App& app, const CLI::ParseError& error) {
  const int code = app.exit(error);  // prints help, the version or the error
  if (dynamic_cast<const CLI::RuntimeError*>(&error) != nullptr) return code;
  return code == 0 ? 0 : kUsageError;
}

std::optional<int> parse(CLI::App& app, int argc, const char* const* argv,
                         std::string_view program) {
  add_version_flag(app, program);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return exit_code(app, e);
  }
  return std::nullopt;
}

}  // namespace swivel::cli
