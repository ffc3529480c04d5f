// SPDX-License-Identifier: Apache-2.0
#include "swivel/daemon/daemon_config.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "swivel/config/config_error.hpp"

namespace swivel::daemon {
namespace {

namespace fs = std::filesystem;

constexpr const char* kValid = R"(loop:
  rate_hz: 500
  fifo_priority: 70
  realtime: false
robot_model: robots/docent.yaml
hardware:
  plugin: sim
  params: {seed: 7}
drivetrain:
  plugin: differential
localization:
  plugin: raw_eg
  params:
    heading_source: encoders
command:
  timeout_s: 0.25
  source: script
  script:
    - {vx_mps: 0.2, duration_s: 1.5}
    - {vx_mps: 0.1, wz_radps: -0.5, duration_s: 2}
plugin_path: [plugins, /opt/swivel/plugins]
logging: {level: debug}
status: {period_s: 0.2}
dds:
  domain_id: 3
  anything: {the bridge: decides}
)";

// A temporary folder holding swiveld.yaml and robots/docent.yaml.
class DaemonConfigTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(testing::TempDir()) /
           ("swivel_config_" +
            std::string(testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::create_directories(dir_ / "robots");
    fs::copy_file(fs::path(SWIVEL_SOURCE_DIR) / "config/robots/docent.yaml",
                  dir_ / "robots/docent.yaml", fs::copy_options::overwrite_existing);
  }
  void TearDown() override { fs::remove_all(dir_); }

  DaemonConfig load(const std::string& text) {
    const fs::path file = dir_ / "swiveld.yaml";
    std::ofstream(file) << text;
    return load_daemon_config(file.string());
  }

  // The message of the ConfigError for `text`, with the folder stripped from file names.
  std::string error_of(const std::string& text) {
    try {
      load(text);
    } catch (const ConfigError& e) {
      std::string message = e.what();
      const std::string prefix = dir_.string() + "/";
      for (auto at = message.find(prefix); at != std::string::npos; at = message.find(prefix)) {
        message.erase(at, prefix.size());
      }
      return message;
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return {};
  }

  static std::string replaced(std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  }

  fs::path dir_;
};

// A reload assigns the new file's localization slot to the running one. The running slot
// must then refer to the new document alone: YAML::Node's own assignment would turn the old
// params node, still held by whatever was configured from it, into an alias of the new one,
// and keep every document the slot was ever given alive in one merged pool.
TEST_F(DaemonConfigTest, AssigningASlotLeavesTheOldParamsAsTheyWere) {
  const std::string gyro = replaced(kValid, "heading_source: encoders", "heading_source: gyro");
  DaemonConfig running = load(kValid);
  const YAML::Node held = running.localization.params;  // as a plugin's context holds it
  const DaemonConfig fresh = load(gyro);
  running.localization = fresh.localization;
  EXPECT_TRUE(running.localization.params.is(fresh.localization.params));
  EXPECT_EQ(running.localization.params["heading_source"].as<std::string>(), "gyro");
  EXPECT_EQ(held["heading_source"].as<std::string>(), "encoders");

  DaemonConfig moved_into = load(kValid);
  const YAML::Node held_before_move = moved_into.localization.params;
  PluginConfig incoming = load(gyro).localization;
  moved_into.localization = std::move(incoming);
  EXPECT_EQ(moved_into.localization.params["heading_source"].as<std::string>(), "gyro");
  EXPECT_EQ(held_before_move["heading_source"].as<std::string>(), "encoders");
}

TEST_F(DaemonConfigTest, ReadsEverySection) {
  const DaemonConfig c = load(kValid);
  EXPECT_EQ(c.rate_hz, 500.0);
  EXPECT_DOUBLE_EQ(c.period_s(), 0.002);
  EXPECT_EQ(c.fifo_priority, 70);
  EXPECT_FALSE(c.realtime);
  EXPECT_EQ(c.robot_model_path, (dir_ / "robots/docent.yaml").string());
  EXPECT_EQ(c.robot.name, "docent");
  EXPECT_EQ(c.hardware.plugin, "sim");
  EXPECT_EQ(c.hardware.params["seed"].as<int>(), 7);
  EXPECT_EQ(c.hardware.params_path, "hardware.params");
  EXPECT_EQ(c.drivetrain.plugin, "differential");
  EXPECT_FALSE(c.drivetrain.params.IsMap());
  EXPECT_EQ(c.localization.params["heading_source"].as<std::string>(), "encoders");
  EXPECT_EQ(c.localization.where, (dir_ / "swiveld.yaml").string() + ":12:3: localization.plugin:");
  EXPECT_EQ(c.command.timeout_s, 0.25);
  EXPECT_EQ(c.command.source, CommandSource::kScript);
  ASSERT_EQ(c.command.script.size(), 2U);
  EXPECT_EQ(c.command.script[0].twist.vx_mps, 0.2);
  EXPECT_EQ(c.command.script[0].twist.wz_radps, 0.0);
  EXPECT_EQ(c.command.script[1].twist.wz_radps, -0.5);
  EXPECT_EQ(c.command.script[1].duration_s, 2.0);
  ASSERT_EQ(c.plugin_path.size(), 2U);
  EXPECT_EQ(c.plugin_path[0], (dir_ / "plugins").string());
  EXPECT_EQ(c.plugin_path[1], "/opt/swivel/plugins");
  EXPECT_EQ(c.log_level, "debug");
  EXPECT_EQ(c.status_period_s, 0.2);
  EXPECT_EQ(c.dds["domain_id"].as<int>(), 3);
}

TEST_F(DaemonConfigTest, DefaultsFillOptionalSections) {
  const DaemonConfig c = load(
      "robot_model: robots/docent.yaml\nhardware: {plugin: sim}\ndrivetrain: {plugin: "
      "differential}\nlocalization: {plugin: raw_eg}\n");
  EXPECT_EQ(c.rate_hz, 1000.0);
  EXPECT_TRUE(c.realtime);
  EXPECT_EQ(c.command.source, CommandSource::kNone);
  EXPECT_EQ(c.command.timeout_s, 0.5);
  EXPECT_EQ(c.log_level, "info");
  EXPECT_TRUE(c.plugin_path.empty());
  EXPECT_FALSE(c.dds.IsDefined() && c.dds.IsMap());
  EXPECT_FALSE(c.has_calibration());
  EXPECT_EQ(c.controlled_stop.linear_deceleration_mps2, 1.0);
  EXPECT_EQ(c.controlled_stop.angular_deceleration_radps2, 2.0);
}

TEST_F(DaemonConfigTest, ControlledStopDecelerationsAreReadAndRangeChecked) {
  const DaemonConfig c = load(replaced(
      kValid, "plugin_path:",
      "controlled_stop: {linear_deceleration_mps2: 0.4, angular_deceleration_radps2: 1.5}\n"
      "plugin_path:"));
  EXPECT_EQ(c.controlled_stop.linear_deceleration_mps2, 0.4);
  EXPECT_EQ(c.controlled_stop.angular_deceleration_radps2, 1.5);
  EXPECT_EQ(error_of(replaced(kValid, "plugin_path:",
                              "controlled_stop: {linear_deceleration_mps2: 0}\nplugin_path:")),
            "swiveld.yaml:21:19: controlled_stop.linear_deceleration_mps2: expected a number in "
            "[0.01, 100], got 0");
}

TEST_F(DaemonConfigTest, TwistWindowIsReadAndBoundedByTheLoopPeriod) {
  EXPECT_EQ(load(kValid).twist_window_s, 0.02);
  const DaemonConfig c =
      load(replaced(kValid, "plugin_path:", "odometry: {twist_window_s: 0.05}\nplugin_path:"));
  EXPECT_EQ(c.twist_window_s, 0.05);
  // loop.rate_hz is 500 here: 2 ms to 0.51 s.
  EXPECT_EQ(
      error_of(replaced(kValid, "plugin_path:", "odometry: {twist_window_s: 0.001}\nplugin_path:")),
      "swiveld.yaml:21:12: odometry.twist_window_s: expected a number of seconds in "
      "[0.002, 0.51] (1 to 255 periods of loop.rate_hz), got 0.001");
  EXPECT_EQ(
      error_of(replaced(kValid, "plugin_path:", "odometry: {twist_window_s: 0.6}\nplugin_path:")),
      "swiveld.yaml:21:12: odometry.twist_window_s: expected a number of seconds in "
      "[0.002, 0.51] (1 to 255 periods of loop.rate_hz), got 0.6");
}

TEST_F(DaemonConfigTest, CalibrationSectionIsOptionalAndValidated) {
  const std::string with =
      replaced(kValid, "command:\n",
               "calibration:\n  plugin: swpc_geometric\n  params: {rotation_deg: 120}\ncommand:\n");
  const DaemonConfig c = load(with);
  ASSERT_TRUE(c.has_calibration());
  EXPECT_EQ(c.calibration.plugin, "swpc_geometric");
  EXPECT_EQ(c.calibration.params["rotation_deg"].as<int>(), 120);
  EXPECT_EQ(c.calibration.params_path, "calibration.params");
  EXPECT_EQ(c.calibration.where, (dir_ / "swiveld.yaml").string() + ":16:3: calibration.plugin:");
  EXPECT_FALSE(load(replaced(kValid, "command:\n", "calibration:\ncommand:\n")).has_calibration());

  EXPECT_EQ(error_of(replaced(with, "  plugin: swpc_geometric\n", "  plugn: swpc_geometric\n")),
            "swiveld.yaml:16:3: calibration: missing required key 'plugin' (expected a string); "
            "is 'plugn' on line 16 a misspelling?");
  EXPECT_EQ(error_of(replaced(with, "  params: {rotation_deg: 120}\n",
                              "  params: {rotation_deg: 120}\n  when: now\n")),
            "swiveld.yaml:18:3: calibration.when: unknown key (known: plugin, params)");
  EXPECT_EQ(error_of(replaced(with, "plugin: swpc_geometric", "plugin: Swpc")),
            "swiveld.yaml:16:3: calibration.plugin: expected a plugin name (lower case, digits, "
            "'_'), got 'Swpc'");
}

TEST_F(DaemonConfigTest, RepositorySwpc4ConfigRunsTheGeometricCalibration) {
  const DaemonConfig c =
      load_daemon_config(std::string(SWIVEL_SOURCE_DIR) + "/config/swiveld_swpc4.yaml");
  EXPECT_EQ(c.robot.name, "swpc4");
  ASSERT_TRUE(c.has_calibration());
  EXPECT_EQ(c.calibration.plugin, "swpc_geometric");
  EXPECT_EQ(c.calibration.params["rotation_deg"].as<double>(), 300.0);
}

TEST_F(DaemonConfigTest, RepositoryDefaultConfigIsValid) {
  const DaemonConfig c =
      load_daemon_config(std::string(SWIVEL_SOURCE_DIR) + "/config/swiveld.yaml");
  EXPECT_EQ(c.rate_hz, 1000.0);
  EXPECT_EQ(c.hardware.plugin, "sim");
  EXPECT_EQ(c.drivetrain.plugin, "differential");
  EXPECT_EQ(c.localization.plugin, "raw_eg");
  EXPECT_EQ(c.robot.name, "docent");
  EXPECT_EQ(c.command.timeout_s, 0.5);
  EXPECT_EQ(c.command.source, CommandSource::kScript);
  EXPECT_GE(c.command.script.size(), 2U);
}

TEST_F(DaemonConfigTest, UnknownKeyListsKnownKeys) {
  EXPECT_EQ(error_of(replaced(kValid, "  rate_hz: 500", "  rat_hz: 500")),
            "swiveld.yaml:2:3: loop.rat_hz: unknown key (known: rate_hz, fifo_priority, "
            "realtime)");
  EXPECT_EQ(error_of(replaced(kValid, "status:", "stats:")),
            "swiveld.yaml:23:1: stats: unknown key (known: loop, robot_model, hardware, "
            "drivetrain, localization, calibration, command, controlled_stop, odometry, "
            "plugin_path, logging, status, dds)");
}

TEST_F(DaemonConfigTest, WrongTypeShowsValue) {
  EXPECT_EQ(error_of(replaced(kValid, "rate_hz: 500", "rate_hz: fast")),
            "swiveld.yaml:2:3: loop.rate_hz: expected a number in [1, 10000], got 'fast'");
  EXPECT_EQ(error_of(replaced(kValid, "realtime: false", "realtime: maybe")),
            "swiveld.yaml:4:3: loop.realtime: expected true or false, got 'maybe'");
  EXPECT_EQ(error_of(replaced(kValid, "fifo_priority: 70", "fifo_priority: 7.5")),
            "swiveld.yaml:3:3: loop.fifo_priority: expected an integer in [1, 99], got '7.5'");
  EXPECT_EQ(error_of(replaced(kValid, "  plugin: sim", "  plugin: [sim]")),
            "swiveld.yaml:7:3: hardware.plugin: expected a non-empty string, got a list");
}

TEST_F(DaemonConfigTest, OutOfRangeNamesTheRange) {
  EXPECT_EQ(error_of(replaced(kValid, "rate_hz: 500", "rate_hz: 20000")),
            "swiveld.yaml:2:3: loop.rate_hz: expected a number in [1, 10000], got 20000");
  EXPECT_EQ(error_of(replaced(kValid, "duration_s: 2}", "duration_s: 0}")),
            "swiveld.yaml:20:37: command.script[1].duration_s: expected a number in [0.001, "
            "86400], got 0");
}

TEST_F(DaemonConfigTest, MissingValueNamesKey) {
  EXPECT_EQ(error_of(replaced(kValid, "drivetrain:\n  plugin: differential\n", "")),
            "swiveld.yaml:1:1: missing required key 'drivetrain'");
  EXPECT_EQ(error_of(replaced(kValid, "  plugin: differential\n", "  params: {}\n")),
            "swiveld.yaml:10:3: drivetrain: missing required key 'plugin' (expected a string)");
  EXPECT_EQ(error_of(replaced(kValid, "  script:\n", "  scrip:\n")),
            "swiveld.yaml:18:3: command.scrip: unknown key (known: timeout_s, source, script)");
  EXPECT_EQ(error_of(replaced(kValid,
                              "  script:\n    - {vx_mps: 0.2, duration_s: 1.5}\n    - {vx_mps: "
                              "0.1, wz_radps: -0.5, duration_s: 2}\n",
                              "  script: []\n")),
            "swiveld.yaml:18:3: command.script: expected a non-empty list of steps when source "
            "is 'script'");
}

TEST_F(DaemonConfigTest, ChoiceListsChoices) {
  EXPECT_EQ(error_of(replaced(kValid, "level: debug", "level: loud")),
            "swiveld.yaml:22:11: logging.level: expected one of trace, debug, info, warn, error, "
            "critical, off, got 'loud'");
  EXPECT_EQ(error_of(replaced(kValid, "source: script", "source: joystick")),
            "swiveld.yaml:17:3: command.source: expected one of script, none, got 'joystick'");
}

TEST_F(DaemonConfigTest, BrokenYamlGivesLineAndColumn) {
  EXPECT_EQ(error_of(replaced(kValid, "status: {period_s: 0.2}", "status: {period_s: 0.2")),
            "swiveld.yaml:24:4: invalid YAML: end of map flow not found");
}

TEST_F(DaemonConfigTest, MissingRobotModelFileIsNamed) {
  EXPECT_EQ(error_of(replaced(kValid, "robots/docent.yaml", "robots/dozent.yaml")),
            "swiveld.yaml:5:1: robot_model: cannot read robot model file 'robots/dozent.yaml' "
            "(looked for robots/dozent.yaml)");
}

TEST_F(DaemonConfigTest, RobotModelErrorsNameTheModelFile) {
  std::ofstream(dir_ / "robots/docent.yaml", std::ios::app) << "colour: blue\n";
  EXPECT_EQ(error_of(kValid),
            "robots/docent.yaml:13:1: colour: unknown key (known: name, drivetrain, "
            "differential, sensors, limits, effects)");
}

TEST_F(DaemonConfigTest, PluginNameMustBeAName) {
  EXPECT_EQ(error_of(replaced(kValid, "plugin: raw_eg", "plugin: ../raw_eg")),
            "swiveld.yaml:12:3: localization.plugin: expected a plugin name (lower case, digits, "
            "'_'), got '../raw_eg'");
}

TEST_F(DaemonConfigTest, ParamsMustBeAMapping) {
  EXPECT_EQ(error_of(replaced(kValid, "params: {seed: 7}", "params: 7")),
            "swiveld.yaml:8:3: hardware.params: expected a mapping, got '7'");
}

TEST_F(DaemonConfigTest, DdsSectionIsLeftToTheBridgeButMustBeAMapping) {
  EXPECT_EQ(error_of(replaced(kValid, "dds:\n  domain_id: 3\n  anything: {the bridge: decides}\n",
                              "dds: [3]\n")),
            "swiveld.yaml:24:1: dds: expected a mapping, got a list");
}

}  // namespace
}  // namespace swivel::daemon
