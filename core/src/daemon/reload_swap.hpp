// SPDX-License-Identifier: Apache-2.0
#pragma once
// The plugin half of a reload: builds what the plan swaps (a localization, and for a new
// robot model a drivetrain and a localization configured for it), validated in full before
// anything changes, hands it to the loop and says how that ended. Errors name what stays.
//
// Main thread only. Not real-time safe.

#include "hot_swap.hpp"
#include "reload_plan.hpp"
#include "swivel/daemon/daemon_config.hpp"
#include "swivel/plugin_loader.hpp"
#include "swivel/types.hpp"

namespace swivel::daemon {

/// What a reload swaps, from the running and the fresh configuration and the plan between
/// them (plan.swap_localization or plan.swap_model set).
struct ReloadSwap {
  const DaemonConfig& running;
  const DaemonConfig& fresh;
  const ReloadPlan& plan;
  PoseEstimate estimate;  ///< the loop's latest: a new localization starts from it
  double wait_s = 2.0;    ///< how long to wait for the loop (a new model: for a cycle at rest)
};

/// Swaps as `swap` says through `hot_swap`. kTaken, or kPending for a localization alone
/// that the loop has not taken yet (the hot swap finishes it later).
/// @throws ConfigError (a model the running robot cannot take, a plugin's parameters) or
///         PluginError (a swap still in flight, a refused hand-over, no rest within wait_s),
///         each saying what stays in effect.
HotSwap::Result apply_reload_swap(HotSwap& hot_swap, PluginLoader& loader, const ReloadSwap& swap);

}  // namespace swivel::daemon
