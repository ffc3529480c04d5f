// SPDX-License-Identifier: Apache-2.0
#include "plugin_set.hpp"

#include <utility>

#include "swivel/plugin/calibration.hpp"

namespace swivel::daemon {
namespace {

void check_module_count(const Drivetrain& drivetrain, const DaemonConfig& config,
                        const RobotModel& robot) {
  if (drivetrain.module_count() != robot.module_count()) {
    throw PluginError(config.drivetrain.where + " plugin '" + config.drivetrain.plugin +
                      "' drives " + std::to_string(drivetrain.module_count()) +
                      " modules, but robot model " + robot.source_file + " has " +
                      std::to_string(robot.module_count()));
  }
}

}  // namespace

std::vector<std::string> plugin_search_path(const DaemonConfig& config) {
  std::vector<std::string> path = config.plugin_path;
  for (auto& dir : PluginLoader::default_search_path()) path.push_back(std::move(dir));
  return path;
}

PluginContext plugin_context(const PluginConfig& slot, const DaemonConfig& config,
                             const RobotModel& robot, double period_s) {
  PluginContext ctx;
  ctx.params = slot.params;
  ctx.config_file = config.file;
  ctx.params_path = slot.params_path;
  ctx.config_dir = config.config_dir;
  ctx.robot = &robot;
  ctx.period_s = period_s;
  return ctx;
}

PluginSet assemble_plugins(PluginLoader& loader, const DaemonConfig& config) {
  const auto context = [&](const PluginConfig& slot) {
    return plugin_context(slot, config, config.robot, config.period_s());
  };
  PluginSet set;
  // Every plugin is loaded before any is configured, so that a missing plugin is reported
  // before another's parameter mistake.
  set.hardware = create_plugin<Hardware>(loader, config.hardware);
  set.drivetrain = create_plugin<Drivetrain>(loader, config.drivetrain);
  set.localization = create_plugin<Localization>(loader, config.localization);
  configure_plugin(*set.hardware, config.hardware, context(config.hardware));
  configure_plugin(*set.drivetrain, config.drivetrain, context(config.drivetrain));
  configure_plugin(*set.localization, config.localization, context(config.localization));
  check_module_count(*set.drivetrain, config, config.robot);
  set.localization->reset(PoseEstimate{});
  if (config.has_calibration()) {
    // Configured once here so that a mistake in its params (or a robot it cannot calibrate)
    // stops the start-up like any other plugin's; each start creates a fresh instance.
    PluginInstance<Calibration> check = create_plugin<Calibration>(loader, config.calibration);
    configure_plugin(*check, config.calibration, context(config.calibration));
  }
  return set;
}

PluginInstance<Localization> make_localization(PluginLoader& loader, const DaemonConfig& fresh,
                                               const RobotModel& robot, double period_s,
                                               const PoseEstimate& estimate) {
  PluginInstance<Localization> next = create_plugin<Localization>(loader, fresh.localization);
  configure_plugin(*next, fresh.localization,
                   plugin_context(fresh.localization, fresh, robot, period_s));
  next->reset(estimate);
  return next;
}

PluginInstance<Drivetrain> make_drivetrain(PluginLoader& loader, const DaemonConfig& running,
                                           const RobotModel& robot) {
  PluginInstance<Drivetrain> next = create_plugin<Drivetrain>(loader, running.drivetrain);
  configure_plugin(*next, running.drivetrain,
                   plugin_context(running.drivetrain, running, robot, running.period_s()));
  check_module_count(*next, running, robot);
  return next;
}

}  // namespace swivel::daemon
