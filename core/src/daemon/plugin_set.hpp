// SPDX-License-Identifier: Apache-2.0
#pragma once
// Assembling the daemon's plugins from its configuration, for the start-up and for a reload
// alike: the search path, creating a plugin from its slot, the context its configure() gets,
// and configuring it, with every error naming the slot in the configuration file.
//
// Not real-time safe (start-up and reload, on the main thread).

#include <string>
#include <vector>

#include "swivel/config/config_error.hpp"
#include "swivel/daemon/daemon_config.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/plugin_loader.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::daemon {

/// The configuration's plugin_path, then PluginLoader::default_search_path().
std::vector<std::string> plugin_search_path(const DaemonConfig& config);

/// What configure() gets for `slot` of `config`: its params, the configuration file and
/// directory, `robot` and the loop period `period_s`. `robot` must outlive the context.
PluginContext plugin_context(const PluginConfig& slot, const DaemonConfig& config,
                             const RobotModel& robot, double period_s);

/// Loads the slot's plugin and creates an instance (not configured).
/// @throws PluginError prefixed with the slot's location.
template <class Interface>
PluginInstance<Interface> create_plugin(PluginLoader& loader, const PluginConfig& slot) {
  try {
    return loader.create<Interface>(slot.plugin);
  } catch (const PluginError& e) {
    throw PluginError(slot.where + " " + e.what());
  }
}

/// Calls plugin.configure(ctx).
/// @throws ConfigError (the plugin's own, naming the key) or PluginError naming the slot's
///         plugin for anything else it throws.
template <class Interface>
void configure_plugin(Interface& plugin, const PluginConfig& slot, const PluginContext& ctx) {
  try {
    plugin.configure(ctx);
  } catch (const ConfigError& e) {
    // A copy made here, not a rethrow: the exception object belongs to the plugin's library,
    // which may be unloaded while the stack unwinds (its instance is destroyed on the way).
    throw ConfigError(e.what());
  } catch (const std::exception& e) {
    throw PluginError(slot.where + " plugin '" + slot.plugin +
                      "' failed to configure: " + e.what());
  }
}

/// The plugins the loop runs.
struct PluginSet {
  PluginInstance<Hardware> hardware;
  PluginInstance<Drivetrain> drivetrain;
  PluginInstance<Localization> localization;
};

/// The start-up's plugins: hardware, drivetrain and localization created, then configured
/// for the configuration's robot model and period; the drivetrain's module count checked
/// against the model; the localization reset at the origin. A `calibration:` plugin is
/// created and configured once to validate its params, then dropped (each calibration
/// creates its own instance).
/// @throws ConfigError or PluginError as above, naming the file, line and key.
PluginSet assemble_plugins(PluginLoader& loader, const DaemonConfig& config);

/// A reload's localization: `fresh.localization` created and configured with the new
/// configuration's params and file, for the robot model `robot` (the running one, or the
/// new one of a model swap) and the loop period `period_s` (unchanged without a restart),
/// then reset to `estimate`.
/// @throws ConfigError or PluginError as above.
PluginInstance<Localization> make_localization(PluginLoader& loader, const DaemonConfig& fresh,
                                               const RobotModel& robot, double period_s,
                                               const PoseEstimate& estimate);

/// A reload's drivetrain for a new robot model: the running configuration's `drivetrain:`
/// slot (its plugin and params change only with a restart) configured for `robot`, with as
/// many modules as the model says.
/// @throws ConfigError (the model's values the plugin refuses, naming the model file) or
///         PluginError as above.
PluginInstance<Drivetrain> make_drivetrain(PluginLoader& loader, const DaemonConfig& running,
                                           const RobotModel& robot);

}  // namespace swivel::daemon
