// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "swivel/config/config_error.hpp"
#include "swivel/daemon/daemon.hpp"

namespace swivel::daemon {
namespace {

namespace fs = std::filesystem;

// swiveld.yaml in a temporary folder, test plugins on its plugin_path.
DaemonConfig config_with(const std::string& sections) {
  const fs::path dir = fs::path(testing::TempDir()) / "swivel_daemon_plugins";
  fs::create_directories(dir);
  const fs::path file = dir / "swiveld.yaml";
  std::ofstream(file) << "robot_model: " << SWIVEL_SOURCE_DIR << "/config/robots/docent.yaml\n"
                      << "plugin_path: [" << SWIVEL_TEST_PLUGIN_DIR << "]\n"
                      << sections;
  return load_daemon_config(file.string());
}

template <class Error>
std::string error_of(const std::string& sections) {
  try {
    Daemon daemon(config_with(sections));
  } catch (const Error& e) {
    const std::string message = e.what();
    return message.substr(message.find("swiveld.yaml"));
  }
  ADD_FAILURE() << "no error for:\n" << sections;
  return {};
}

TEST(DaemonPlugins, UnknownPluginNamesTheConfigLineAndSearchPath) {
  const std::string error = error_of<PluginError>(
      "hardware: {plugin: simm}\ndrivetrain: {plugin: differential}\n"
      "localization: {plugin: raw_eg}\n");
  EXPECT_EQ(error.rfind("swiveld.yaml:3:12: hardware.plugin: hardware plugin 'simm' not found: "
                        "no swivel_hardware_simm.so in " SWIVEL_TEST_PLUGIN_DIR ", ",
                        0),
            0U)
      << error;
}

TEST(DaemonPlugins, PluginOfAnotherKindIsRefused) {
  // The test folder has swivel_localization_good.so, but nothing of kind drivetrain.
  const std::string error = error_of<PluginError>(
      "hardware: {plugin: sim}\ndrivetrain: {plugin: good}\nlocalization: {plugin: good}\n");
  EXPECT_EQ(error.rfind("swiveld.yaml:4:14: drivetrain.plugin: drivetrain plugin 'good' not "
                        "found: no swivel_drivetrain_good.so in ",
                        0),
            0U)
      << error;
}

TEST(DaemonPlugins, ConfigureErrorOfAPluginNamesItsParamKey) {
  const std::string error = error_of<ConfigError>(
      "hardware: {plugin: sim}\ndrivetrain: {plugin: differential}\n"
      "localization:\n  plugin: throws_configure\n  params:\n    gain: 2\n");
  EXPECT_EQ(error,
            "swiveld.yaml:8:5: localization.params.gain: expected a number in [0, 1], got 2");
}

TEST(DaemonPlugins, ValidConfigurationConfiguresEveryPlugin) {
  Daemon daemon(
      config_with("hardware: {plugin: sim}\ndrivetrain: {plugin: differential}\n"
                  "localization: {plugin: good, params: {start_x_m: 1.0}}\n"));
  EXPECT_EQ(daemon.config().localization.plugin, "good");
  EXPECT_EQ(daemon.loop(), nullptr) << "nothing runs before start()";
}

}  // namespace
}  // namespace swivel::daemon
