// SPDX-License-Identifier: Apache-2.0
#pragma once
// swivel-bench swap: how long a localization hot swap takes, from the request to the new
// plugin's first update on the loop, while the loop runs at its rate with the plugins of a
// daemon configuration (docs/architecture.md "Reload and hot swap").

#include <string>

namespace swivel::bench {

struct SwapSettings {
  int swaps = 60;            ///< swaps to time, cycling kalman -> lsm -> raw_eg
  double interval_s = 0.05;  ///< pause between swaps
  double rate_hz = 1000.0;
  int priority = 80;
  bool realtime = true;
  std::string config;  ///< daemon configuration naming the other plugins
};

/// Prints the figures; returns the process exit code (1 when the plugins cannot be loaded or
/// a swap is not taken).
int run_swap(const SwapSettings& settings);

}  // namespace swivel::bench
