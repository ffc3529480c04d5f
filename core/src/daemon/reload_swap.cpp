// SPDX-License-Identifier: Apache-2.0
#include "reload_swap.hpp"

#include <fmt/format.h>

#include <string>

#include "plugin_set.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {

HotSwap::Result apply_reload_swap(HotSwap& hot_swap, PluginLoader& loader, const ReloadSwap& swap) {
  const DaemonConfig& running = swap.running;
  const DaemonConfig& fresh = swap.fresh;
  const bool new_model = swap.plan.swap_model;
  if (new_model) {
    if (const std::string problem = model_swap_problem(running.robot, fresh.robot);
        !problem.empty()) {
      throw ConfigError(fresh.robot_model_path + ": " + problem + "; still running on " +
                        running.robot_model_path);
    }
  }
  (void)hot_swap.collect();
  if (hot_swap.busy()) throw PluginError("the previous swap has not completed yet; try again");

  // For a new model, a drivetrain (the running slot) and a localization configured for it;
  // otherwise a localization for the model in effect.
  const RobotModel& robot = new_model ? fresh.robot : running.robot;
  HotSwap::Incoming next;
  next.localization = make_localization(loader, fresh, robot, running.period_s(), swap.estimate);
  next.localization_slot = fresh.localization;
  if (new_model) {
    next.drivetrain = make_drivetrain(loader, running, fresh.robot);
    next.model = rt::model_settings(fresh.robot);
  }

  std::string refusal;
  const HotSwap::Result swapped = hot_swap.exchange(std::move(next), swap.wait_s, &refusal);
  if (swapped == HotSwap::Result::kNotAtRest) {
    throw PluginError(fmt::format(
        "robot_model: applies with the robot at rest; it did not come to rest within {:g} s "
        "(stop it and reload again); still running on {}",
        swap.wait_s, running.robot_model_path));
  }
  if (swapped == HotSwap::Result::kRefused) {
    throw PluginError(
        fresh.localization.where + " plugin '" + fresh.localization.plugin +
        "' refused the hand-over: " + refusal + "; '" + running.localization.plugin +
        "' stays active" +
        (new_model ? " and robot_model stays " + running.robot_model_path : std::string()));
  }
  if (new_model && swapped != HotSwap::Result::kTaken) {
    throw PluginError("robot_model: the loop did not take the new model; still running on " +
                      running.robot_model_path);
  }
  return swapped;
}

}  // namespace swivel::daemon
