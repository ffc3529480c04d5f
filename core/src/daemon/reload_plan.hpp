// SPDX-License-Identifier: Apache-2.0
#pragma once
// What a configuration reload changes: a pure function from the running configuration and
// the newly read one to a plan (what applies live, what needs a restart), with no plugin,
// loop or file behind it, so that the rules are tested on their own.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "swivel/daemon/daemon_config.hpp"

namespace swivel::daemon {

struct ReloadPlan {
  /// Changed settings that only a restart applies, in the order of the configuration
  /// reference: loop.rate_hz, loop.fifo_priority, loop.realtime, hardware, drivetrain,
  /// command, plugin_path, dds, calibration, controlled_stop, odometry.
  std::vector<std::string> restart;
  /// The localization's plugin or params changed: build the new one and hot-swap it.
  bool swap_localization = false;
  /// robot_model changed (its path or its file's contents): build the drivetrain and the
  /// localization for the new model and swap them in together, with the robot at rest.
  /// model_swap_problem() says whether the running robot can take it at all.
  bool swap_model = false;
  /// A new logging.level, when it changed.
  std::optional<std::string> log_level;
  /// A new status.period_s, when it changed.
  std::optional<double> status_period_s;

  /// Nothing to apply live (a restart may still be needed).
  [[nodiscard]] bool no_live_change() const {
    return !swap_localization && !swap_model && !log_level && !status_period_s;
  }
};

/// The plan for going from `running` to `fresh`. The model texts are the robot model files'
/// contents (the running one as it was read at start-up, the fresh one now), so that an
/// edited model file counts as a change even under the same path.
ReloadPlan plan_reload(const DaemonConfig& running, std::string_view running_model_text,
                       const DaemonConfig& fresh, std::string_view fresh_model_text);

/// Why the running robot cannot take `fresh` as its new model, or "" when it can: the
/// hardware keeps what it was built with, so the drivetrain kind and the module count must
/// stay, and the robot's name (the DDS key of its topics) as well.
std::string model_swap_problem(const RobotModel& running, const RobotModel& fresh);

/// `items` joined by ", ".
std::string comma_list(const std::vector<std::string>& items);

/// The reload's one-line outcome: "applied A, B" or "no live change", followed by
/// "; needs a restart: X, Y" when `restart` is not empty.
std::string describe_reload(const std::vector<std::string>& applied,
                            const std::vector<std::string>& restart);

}  // namespace swivel::daemon
