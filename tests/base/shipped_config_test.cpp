// SPDX-License-Identifier: Apache-2.0
// Where the shipped configuration is found: the source tree's config/ for executables in
// the build tree, <sysconfdir>/swivel for installed ones, whatever the working directory.

#include "swivel/shipped_config.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

namespace swivel {
namespace {

std::string build_dir() {
  const char* dir = std::getenv("SWIVEL_BUILD_DIR");
  return dir != nullptr ? dir : "";
}

TEST(ShippedConfig, BuildTreeExecutablesUseTheSourceTree) {
  ASSERT_FALSE(build_dir().empty()) << "ctest sets SWIVEL_BUILD_DIR";
  EXPECT_EQ(shipped_config_dir_for(build_dir() + "/bin/swivel-lab"), SWIVEL_SOURCE_CONFIG_DIR);
  EXPECT_EQ(shipped_config_dir_for(build_dir() + "/tests/../bin/swivel-lab"),
            SWIVEL_SOURCE_CONFIG_DIR);
}

TEST(ShippedConfig, OtherExecutablesUseTheInstalledCopy) {
  ASSERT_FALSE(build_dir().empty()) << "ctest sets SWIVEL_BUILD_DIR";
  EXPECT_EQ(shipped_config_dir_for(std::string(SWIVEL_INSTALLED_BIN_DIR) + "/swivel-lab"),
            SWIVEL_INSTALLED_CONFIG_DIR);
  EXPECT_EQ(shipped_config_dir_for("/opt/elsewhere/bin/swivel-lab"), SWIVEL_INSTALLED_CONFIG_DIR);
  // A sibling whose name merely starts like the build directory is not inside it.
  EXPECT_EQ(shipped_config_dir_for(build_dir() + "-other/bin/swivel-lab"),
            SWIVEL_INSTALLED_CONFIG_DIR);
}

// The Debian packages install /usr/bin and /etc/swivel whatever the configured prefix: for a
// /usr build that is the configured layout, for a /usr/local one the package's own.
TEST(ShippedConfig, PackagedExecutablesUseTheConfigurationInEtc) {
  const std::filesystem::path expected = std::string_view(SWIVEL_INSTALLED_BIN_DIR) == "/usr/bin"
                                             ? SWIVEL_INSTALLED_CONFIG_DIR
                                             : "/etc/swivel";
  EXPECT_EQ(shipped_config_dir_for("/usr/bin/swivel-lab"), expected);
  EXPECT_EQ(shipped_config_dir_for("/usr/bin/../bin/swivelctl"), expected);
}

TEST(ShippedConfig, ThisTestFindsTheRepositoryFromAnyWorkingDirectory) {
  const auto before = std::filesystem::current_path();
  std::filesystem::current_path(std::filesystem::temp_directory_path());
  const auto file = shipped_config_file("robots/docent.yaml");
  std::filesystem::current_path(before);
  EXPECT_EQ(file, std::filesystem::path(SWIVEL_SOURCE_CONFIG_DIR) / "robots/docent.yaml");
  EXPECT_TRUE(std::filesystem::exists(file)) << file;
}

}  // namespace
}  // namespace swivel
