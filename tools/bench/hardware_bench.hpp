// SPDX-License-Identifier: Apache-2.0
#pragma once
// swivel-bench hardware: the `dynamixel` plugin on an emulated bus. For 2 servos (the docent)
// and 8 (the four-module SWPC robot) at 1 and 4 Mbps: the bus round trip of one cycle
// (Sync Write of goals + Sync Read of present values) with the wire time emulated, the
// highest loop rate at which every cycle can have a fresh reading, and the loop's lateness
// with the plugin loaded like the daemon loads it, against the bare-sleep floor; each with
// every servo's Bus Watchdog armed (0.1 s) and its expiries counted.

#include <string>

namespace swivel::bench {

struct HardwareSettings {
  double seconds = 3.0;    ///< per measurement
  double rate_hz = 500.0;  ///< loop rate of the lateness phases
  int priority = 80;
  bool realtime = true;
  std::string robots_dir;  ///< config/robots
};

int run_hardware(const HardwareSettings& settings);

}  // namespace swivel::bench
