// SPDX-License-Identifier: Apache-2.0
// The version every executable reports: CMake's project(VERSION) and, from a git checkout,
// `git describe` at configure time.

#include "swivel/version.hpp"

#include <gtest/gtest.h>

#include <string>

namespace swivel {
namespace {

TEST(Version, IsTheProjectVersion) { EXPECT_EQ(version(), SWIVEL_EXPECTED_VERSION); }

TEST(Version, LineNamesTheProgramTheVersionAndTheCheckout) {
  const std::string describe(git_describe());
  const std::string expected = std::string("swiveld ") + SWIVEL_EXPECTED_VERSION +
                               (describe.empty() ? "" : " (git " + describe + ")");
  EXPECT_EQ(version_line("swiveld"), expected);
}

TEST(Version, DescribeIsWhatGitSaidAtConfigureTime) {
  // What CMake found (empty when not built from a checkout, or without git), as compiled in.
  EXPECT_EQ(git_describe(), SWIVEL_EXPECTED_DESCRIBE);
}

}  // namespace
}  // namespace swivel
