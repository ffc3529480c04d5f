// SPDX-License-Identifier: Apache-2.0
#pragma once
// The daemon's configuration file (config/swiveld.yaml), read and validated in full before
// anything starts. Start-up code: throws ConfigError naming file:line:column and key.

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::daemon {

/// One plugin slot: `{plugin: NAME, params: {...}}`. The plugin validates its own params.
///
/// Assigning a slot makes `params` refer to the other slot's node (YAML::Node::reset()).
/// YAML::Node's own assignment would instead merge the other document's node pool into this
/// one's, for as long as either lives: the running slot, assigned the slot of each swap a
/// reload brings, kept every such configuration file (about 70 KB each for the default one).
// NOLINTNEXTLINE(bugprone-exception-escape): YAML::Node moves by copying, which may allocate
struct PluginConfig {
  std::string plugin;       ///< plugin name, e.g. "differential"
  YAML::Node params;        ///< the `params:` mapping (null when absent)
  std::string params_path;  ///< "drivetrain.params", for messages
  std::string where;        ///< "swiveld.yaml:14:11: drivetrain.plugin:", for messages

  PluginConfig() = default;
  PluginConfig(const PluginConfig&) = default;  // shares the other's node: nothing merges
  PluginConfig(PluginConfig&&) = default;
  PluginConfig& operator=(const PluginConfig& other);
  // Throws as YAML::Node's own assignment does, for an invalid node (a failed lookup's).
  // NOLINTNEXTLINE(performance-noexcept-move-constructor,bugprone-exception-escape)
  PluginConfig& operator=(PluginConfig&& other);
  ~PluginConfig() = default;
};

/// One step of the built-in motion script: hold `twist` for `duration_s`.
struct ScriptStep {
  Twist2 twist;
  double duration_s = 1.0;
};

enum class CommandSource { kScript, kNone };

struct CommandConfig {
  double timeout_s = 0.5;  ///< a velocity command older than this stops the robot
  CommandSource source = CommandSource::kNone;
  std::vector<ScriptStep> script;  ///< played in a loop when source is kScript
};

/// `controlled_stop:`: how fast the daemon brings the robot to rest on its own (a fault, a
/// command timeout, SIGTERM/SIGINT) on the axes whose robot model has no acceleration limit
/// in `limits:`; where the model has one, the stop uses the model's.
struct ControlledStopConfig {
  double linear_deceleration_mps2 = 1.0;     ///< body x and y, each on its own
  double angular_deceleration_radps2 = 2.0;  ///< yaw
};

struct DaemonConfig {
  std::string file;        ///< the configuration file as given
  std::string config_dir;  ///< its directory: base of relative paths

  double rate_hz = 1000.0;  ///< loop.rate_hz
  int fifo_priority = 80;   ///< loop.fifo_priority (SCHED_FIFO, 1..99)
  bool realtime = true;     ///< loop.realtime: try SCHED_FIFO, mlockall, cpu_dma_latency

  std::string robot_model_path;  ///< resolved path of robot_model
  RobotModel robot;              ///< the nominal robot model, loaded and validated

  PluginConfig hardware;
  PluginConfig drivetrain;
  PluginConfig localization;
  /// `calibration:` (optional): the calibration plugin `swivelctl calibrate` runs; its
  /// `plugin` is empty when the section is absent (calibrate requests are then refused).
  PluginConfig calibration;

  CommandConfig command;
  ControlledStopConfig controlled_stop;
  /// odometry.twist_window_s: the published twist is fitted over the readings of this
  /// window (rt::LoopOptions::twist_window_s); one loop period to 255 periods.
  double twist_window_s = 0.02;
  std::vector<std::string> plugin_path;  ///< searched before the default search path
  std::string log_level = "info";        ///< spdlog level name
  double status_period_s = 1.0;          ///< status line period on stdout
  YAML::Node dds;  ///< the `dds:` mapping, validated by the DDS bridge (null when absent)

  [[nodiscard]] double period_s() const { return 1.0 / rate_hz; }
  [[nodiscard]] bool has_calibration() const { return !calibration.plugin.empty(); }
};

/// Reads, validates and resolves a configuration file (the robot model included).
/// @throws ConfigError naming file:line:column, the key and what was expected.
DaemonConfig load_daemon_config(const std::string& path);

/// As load_daemon_config, from text; `file` names it in messages and `config_dir` is the
/// base of relative paths.
DaemonConfig parse_daemon_config(const std::string& yaml_text, const std::string& file,
                                 const std::string& config_dir);

/// The log level names accepted by logging.level and --log-level.
const std::vector<std::string>& log_level_names();

}  // namespace swivel::daemon
