// SPDX-License-Identifier: Apache-2.0
#pragma once
// Configurations of swiveld with the `dynamixel` hardware plugin on servos emulated on a
// pseudo-terminal (swivel::dynamixel::Emulator), for the integration tests.

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "process_util.hpp"
#include "swivel/dynamixel/emulator.hpp"

namespace swivel::test {

/// An emulated bus with servos of these IDs.
inline dynamixel::Emulator::Options servo_ids(std::vector<std::uint8_t> ids) {
  dynamixel::Emulator::Options o;
  o.ids = std::move(ids);
  return o;
}

/// The docent's two wheel servos (IDs 1 and 2, the right one mounted reversed) on `port`.
/// Reply timeout and stale limit generous enough for a loaded test machine (the emulator is
/// an ordinary thread).
inline std::string docent_params(const std::string& port) {
  return "{port: " + port +
         ", reply_timeout_s: 0.2, stale_timeout_s: 1.0, left: {id: 1}, right: {id: 2, "
         "direction: -1}}";
}

/// A configuration file in `dir` for `robot` (docent or swpc4) with the given hardware
/// params and motion script, raw_eg taking its heading from `heading_source` and status lines
/// every 0.1 s; `more_yaml` adds top-level sections (dds:). Returns its path.
inline std::string write_config(const std::string& dir, const std::string& robot,
                                const std::string& hardware_params, const std::string& script,
                                const std::string& heading_source = "encoders",
                                const std::string& more_yaml = "") {
  const bool differential = robot == "docent";
  std::ostringstream c;
  c << "loop: {rate_hz: 500, realtime: false}\n"
    << "robot_model: " << source_dir() << "/config/robots/" << robot << ".yaml\n"
    << "hardware:\n  plugin: dynamixel\n  params: " << hardware_params << "\n"
    << "drivetrain:\n  plugin: " << (differential ? "differential" : "swpc") << "\n"
    << "  params: {max_wheel_rate_radps: 20.0"
    << (differential ? "" : ", max_steer_rate_radps: 6.0") << "}\n"
    << "localization: {plugin: raw_eg, params: {heading_source: " << heading_source << "}}\n"
    << "command:\n  timeout_s: 0.5\n  source: script\n  script:\n"
    << script << "logging: {level: info}\nstatus: {period_s: 0.1}\n"
    << more_yaml;
  std::string path = dir + "/swiveld.yaml";
  std::ofstream(path) << c.str();
  return path;
}

}  // namespace swivel::test
