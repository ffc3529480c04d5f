// SPDX-License-Identifier: Apache-2.0
// swivel::cli: --version and exit code 2 on usage errors, on a command line like the tools'.

#include "swivel/cli/command_line.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "swivel/version.hpp"

namespace swivel::cli {
namespace {

struct Parsed {
  std::optional<int> exit;
  std::string out;
  std::string err;
};

// A small command line like the tools': a required option, a ranged number, a subcommand
// whose callback ends the program with its own code.
Parsed parse_args(std::vector<std::string> args) {
  CLI::App app{"test program"};
  std::string config;
  double rate_hz = 1.0;
  app.add_option("--config", config, "configuration")->required();
  app.add_option("--rate-hz", rate_hz, "rate")->check(CLI::Range(1.0, 100.0));
  CLI::App* sub = app.add_subcommand("finish", "ends with code 7");
  sub->callback([] { throw CLI::RuntimeError(7); });
  args.insert(args.begin(), "prog");
  std::vector<const char*> argv;
  argv.reserve(args.size());
  for (const auto& a : args) argv.push_back(a.c_str());
  Parsed parsed;
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  parsed.exit = parse(app, static_cast<int>(argv.size()), argv.data(), "prog");
  parsed.out = testing::internal::GetCapturedStdout();
  parsed.err = testing::internal::GetCapturedStderr();
  return parsed;
}

TEST(CommandLine, ValidArgumentsLetTheProgramGoOn) {
  const Parsed p = parse_args({"--config", "a.yaml", "--rate-hz", "10"});
  EXPECT_FALSE(p.exit.has_value());
  EXPECT_EQ(p.out, "");
  EXPECT_EQ(p.err, "");
}

TEST(CommandLine, UsageErrorsExitWithTwoAndSayWhy) {
  const Parsed unknown = parse_args({"--config", "a.yaml", "--no-such-option"});
  EXPECT_EQ(unknown.exit, kUsageError);
  EXPECT_NE(unknown.err.find("--no-such-option"), std::string::npos) << unknown.err;

  const Parsed missing = parse_args({});
  EXPECT_EQ(missing.exit, kUsageError);
  EXPECT_NE(missing.err.find("--config is required"), std::string::npos) << missing.err;

  const Parsed out_of_range = parse_args({"--config", "a.yaml", "--rate-hz", "1000"});
  EXPECT_EQ(out_of_range.exit, kUsageError);
  EXPECT_NE(out_of_range.err.find("--rate-hz"), std::string::npos) << out_of_range.err;

  const Parsed not_a_number = parse_args({"--config", "a.yaml", "--rate-hz", "fast"});
  EXPECT_EQ(not_a_number.exit, kUsageError);
}

TEST(CommandLine, HelpAndVersionExitWithZeroOnStdout) {
  const Parsed help = parse_args({"--help"});
  EXPECT_EQ(help.exit, 0);
  EXPECT_NE(help.out.find("--version"), std::string::npos) << help.out;

  // Before the required option is checked, as --help is.
  const Parsed version = parse_args({"--version"});
  EXPECT_EQ(version.exit, 0);
  EXPECT_EQ(version.out, version_line("prog") + "\n");
  EXPECT_EQ(version.err, "");
}

TEST(CommandLine, ACallbacksOwnExitCodePassesThrough) {
  const Parsed p = parse_args({"--config", "a.yaml", "finish"});
  EXPECT_EQ(p.exit, 7);
  EXPECT_EQ(p.err, "");
}

}  // namespace
}  // namespace swivel::cli
