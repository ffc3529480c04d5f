// SPDX-License-Identifier: Apache-2.0
#include "swivel/shipped_config.hpp"

namespace swivel {
namespace {

bool is_under(const std::filesystem::path& path, const std::filesystem::path& dir) {
  const auto rel = path.lexically_normal().lexically_relative(dir.lexically_normal());
  return !rel.empty() && *rel.begin() != "..";
}

}  // namespace

std::filesystem::path shipped_config_dir_for(const std::filesystem::path& executable) {
  std::error_code ec;
  std::filesystem::path build_dir = std::filesystem::weakly_canonical(SWIVEL_BUILD_DIR, ec);
  if (ec) build_dir = SWIVEL_BUILD_DIR;
  if (is_under(executable, build_dir) || is_under(executable, SWIVEL_BUILD_DIR)) {
    return SWIVEL_SOURCE_CONFIG_DIR;
  }
  // The Debian packages put the executables in /usr/bin and the configuration in /etc/swivel
  // whatever prefix the build was configured with (services/CMakeLists.txt).
  const std::filesystem::path dir = executable.lexically_normal().parent_path();
  if (dir != std::filesystem::path(SWIVEL_INSTALLED_BIN_DIR) && dir == "/usr/bin") {
    return "/etc/swivel";
  }
  return SWIVEL_INSTALLED_CONFIG_DIR;
}

std::filesystem::path shipped_config_dir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path(SWIVEL_INSTALLED_CONFIG_DIR) : shipped_config_dir_for(exe);
}

std::filesystem::path shipped_config_file(std::string_view relative) {
  return shipped_config_dir() / relative;
}

}  // namespace swivel
