// SPDX-License-Identifier: Apache-2.0
// Every Swivel executable answers --version with the project's version and exits 2 on a
// usage error, whatever library parses its command line (CLI11 or Google Benchmark).

#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "process_util.hpp"
#include "swivel/version.hpp"

namespace swivel::test {
namespace {

std::vector<std::string> executables() {
  std::vector<std::string> paths;
  std::istringstream in(SWIVEL_EXECUTABLES);
  for (std::string path; std::getline(in, path, ':');) {
    if (!path.empty()) paths.push_back(path);
  }
  return paths;
}

ToolRun run(const std::string& exe, const std::vector<std::string>& args) {
  Child child(exe, args);
  ToolRun result;
  result.exit_code = child.exit_code(Seconds(20));
  result.out = child.out();
  result.err = child.err();
  return result;
}

// Every executable in the build's bin/ (what the packages install) is among those tested
// here, and each one tested was built.
TEST(Executables, AllAreTested) {
  namespace fs = std::filesystem;
  std::set<std::string> tested;
  for (const auto& exe : executables()) {
    EXPECT_TRUE(fs::is_regular_file(exe)) << exe << " was not built";
    tested.insert(fs::path(exe).filename().string());
  }
  EXPECT_TRUE(tested.contains("swiveld")) << SWIVEL_EXECUTABLES;
  EXPECT_TRUE(tested.contains("swivelctl")) << SWIVEL_EXECUTABLES;
  std::size_t in_bin = 0;
  for (const auto& entry : fs::directory_iterator(SWIVEL_BIN_DIR)) {
    if (!entry.is_regular_file() ||
        (entry.status().permissions() & fs::perms::owner_exec) == fs::perms::none) {
      continue;
    }
    ++in_bin;
    EXPECT_TRUE(tested.contains(entry.path().filename().string()))
        << entry.path() << " is not tested: no target of this build writes it (a stale file of "
        << "a renamed target?)";
  }
  EXPECT_EQ(in_bin, tested.size());
}

TEST(Executables, VersionPrintsTheProjectVersion) {
  for (const auto& exe : executables()) {
    const std::string name = std::filesystem::path(exe).filename().string();
    const ToolRun r = run(exe, {"--version"});
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.err;
    EXPECT_EQ(r.out, version_line(name) + "\n") << name;
    EXPECT_EQ(r.out.rfind(name + " " + SWIVEL_EXPECTED_VERSION, 0), 0U) << r.out;
  }
}

TEST(Executables, AnUnknownOptionIsAUsageError) {
  for (const auto& exe : executables()) {
    const std::string name = std::filesystem::path(exe).filename().string();
    const ToolRun r = run(exe, {"--no-such-option"});
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.out << r.err;
    // CLI11 may report a missing required option or subcommand first; either way it says why.
    EXPECT_NE(r.err, "") << name;
    EXPECT_EQ(r.out.find("Usage"), std::string::npos) << name << " printed its help instead";
  }
}

}  // namespace
}  // namespace swivel::test
