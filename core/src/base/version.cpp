// SPDX-License-Identifier: Apache-2.0
#include "swivel/version.hpp"

#include "version_info.hpp"

namespace swivel {

std::string_view version() noexcept { return kVersion; }

std::string_view git_describe() noexcept { return kGitDescribe; }

std::string version_line(std::string_view program) {
  std::string line(program);
  line += ' ';
  line += version();
  if (!git_describe().empty()) {
    line += " (git ";
    line += git_describe();
    line += ')';
  }
  return line;
}

}  // namespace swivel
