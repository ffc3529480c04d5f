// SPDX-License-Identifier: Apache-2.0
// YAML text -> parse_daemon_config. Contract: a configuration or ConfigError, nothing else.
// Relative paths resolve against config_dir/, which holds the robot models the corpus names.

#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/daemon/daemon_config.hpp"

// The entry point libFuzzer names.
// NOLINTNEXTLINE(readability-identifier-naming)
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // The parser opens whatever robot_model names; keep the fuzzer out of the rest of the
  // file system (/dev, /proc, large files) by refusing any path separator.
  if (text.find('/') != std::string::npos) return 0;
  try {
    (void)swivel::daemon::parse_daemon_config(text, "fuzz.yaml", SWIVEL_FUZZ_CONFIG_DIR);
  } catch (const swivel::ConfigError&) {
  } catch (const std::exception& e) {
    swivel::fuzz::unexpected_exception("fuzz_daemon_config", e);
  }
  return 0;
}
