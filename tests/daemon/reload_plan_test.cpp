// SPDX-License-Identifier: Apache-2.0
// The reload plan: what a changed configuration applies live and what waits for a restart,
// computed from two configurations alone (no plugin, loop or process).

#include "reload_plan.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "swivel/robot_model_io.hpp"

namespace swivel::daemon {
namespace {

const std::string config_dir = SWIVEL_SOURCE_DIR "/config";

std::string shipped_text() {
  std::ifstream in(config_dir + "/swiveld.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The shipped configuration with `from` replaced by `to` (which must occur once).
DaemonConfig edited(const std::string& from, const std::string& to) {
  std::string text = shipped_text();
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return parse_daemon_config(text, "swiveld.yaml", config_dir);
}

DaemonConfig shipped() { return parse_daemon_config(shipped_text(), "swiveld.yaml", config_dir); }

const std::string model_text = "name: docent\n";

ReloadPlan plan_for(const DaemonConfig& fresh, const std::string& fresh_model = model_text) {
  return plan_reload(shipped(), model_text, fresh, fresh_model);
}

TEST(ReloadPlan, AnUnchangedConfigurationChangesNothing) {
  const ReloadPlan plan = plan_for(shipped());
  EXPECT_TRUE(plan.restart.empty());
  EXPECT_TRUE(plan.no_live_change());
  EXPECT_EQ(describe_reload({}, plan.restart), "no live change");
}

TEST(ReloadPlan, ALocalizationChangeIsSwappedLive) {
  const ReloadPlan plugin = plan_for(edited("plugin: raw_eg", "plugin: kalman"));
  EXPECT_TRUE(plugin.swap_localization);
  EXPECT_TRUE(plugin.restart.empty());

  // New parameters of the same plugin are a swap as well.
  const ReloadPlan params = plan_for(edited("heading_source: gyro ", "heading_source: encoders "));
  EXPECT_TRUE(params.swap_localization);
  EXPECT_TRUE(params.restart.empty());
}

TEST(ReloadPlan, LogLevelAndStatusPeriodApplyLive) {
  const ReloadPlan level = plan_for(edited("level: info", "level: debug"));
  ASSERT_TRUE(level.log_level.has_value());
  EXPECT_EQ(*level.log_level, "debug");
  EXPECT_FALSE(level.status_period_s.has_value());

  const ReloadPlan period = plan_for(edited("period_s: 0.5", "period_s: 2"));
  ASSERT_TRUE(period.status_period_s.has_value());
  EXPECT_DOUBLE_EQ(*period.status_period_s, 2.0);
  EXPECT_FALSE(period.swap_localization);
  EXPECT_TRUE(period.restart.empty());
}

TEST(ReloadPlan, EachRestartSettingIsNamed) {
  const std::vector<std::pair<std::pair<std::string, std::string>, std::string>> cases = {
      {{"rate_hz: 1000", "rate_hz: 500"}, "loop.rate_hz"},
      {{"fifo_priority: 80", "fifo_priority: 70"}, "loop.fifo_priority"},
      {{"realtime: true", "realtime: false"}, "loop.realtime"},
      {{"seed: 1 ", "seed: 2 "}, "hardware"},
      {{"max_wheel_rate_radps: 20.0", "max_wheel_rate_radps: 15.0"}, "drivetrain"},
      {{"timeout_s: 0.5", "timeout_s: 0.25"}, "command"},
      {{"source: script ", "source: none "}, "command"},
      {{"duration_s: 3.333}", "duration_s: 3.0}"}, "command"},
      {{"linear_deceleration_mps2: 1.0", "linear_deceleration_mps2: 2.0"}, "controlled_stop"},
      {{"angular_deceleration_radps2: 2.0", "angular_deceleration_radps2: 3.0"}, "controlled_stop"},
      {{"twist_window_s: 0.02", "twist_window_s: 0.05"}, "odometry"},
      {{"domain_id: 0 ", "domain_id: 7 "}, "dds"},
      {{"enabled: false", "enabled: true"}, "dds"},
      {{"robot_model:", "plugin_path: [/nonexistent]\nrobot_model:"}, "plugin_path"},
      {{"robot_model:", "calibration: {plugin: swpc_geometric}\nrobot_model:"}, "calibration"},
  };
  for (const auto& [edit, name] : cases) {
    const ReloadPlan plan = plan_for(edited(edit.first, edit.second));
    EXPECT_EQ(plan.restart, std::vector<std::string>{name}) << edit.second;
    EXPECT_TRUE(plan.no_live_change()) << edit.second;
  }
}

TEST(ReloadPlan, AnEditedRobotModelFileIsSwappedLiveUnderTheSamePath) {
  const ReloadPlan edited_file = plan_for(shipped(), "name: docent\n# edited\n");
  EXPECT_TRUE(edited_file.swap_model);
  EXPECT_FALSE(edited_file.swap_localization);  // its slot is unchanged; the daemon rebuilds it
  EXPECT_TRUE(edited_file.restart.empty());
  EXPECT_FALSE(edited_file.no_live_change());
  EXPECT_FALSE(plan_for(shipped()).swap_model);
}

TEST(ReloadPlan, AnotherRobotModelPathIsAModelSwap) {
  // Whether the running robot can take that model is model_swap_problem()'s to say.
  const ReloadPlan plan = plan_for(
      edited("robot_model: robots/docent.yaml", "robot_model: robots/swpc4.yaml"), model_text);
  EXPECT_TRUE(plan.swap_model);
  EXPECT_TRUE(plan.restart.empty());
}

TEST(ReloadPlan, AModelChangeTogetherWithALocalizationChangeSwapsBoth) {
  const ReloadPlan plan = plan_for(edited("plugin: raw_eg", "plugin: kalman"), "name: docent\n#\n");
  EXPECT_TRUE(plan.swap_model);
  EXPECT_TRUE(plan.swap_localization);
  EXPECT_TRUE(plan.restart.empty());
}

TEST(ReloadPlan, AModelTheRunningRobotCannotTakeIsNamed) {
  const RobotModel docent = load_robot_model(config_dir + "/robots/docent.yaml");
  const RobotModel swpc4 = load_robot_model(config_dir + "/robots/swpc4.yaml");
  RobotModel wider = docent;
  wider.differential.track_width_m *= 1.04;
  wider.differential.wheel_radius_left_m = 0.08;
  wider.limits.linear_velocity_mps = 0.5;
  EXPECT_EQ(model_swap_problem(docent, wider), "");
  EXPECT_EQ(model_swap_problem(docent, docent), "");

  const std::string kind = model_swap_problem(docent, swpc4);
  EXPECT_NE(kind.find("drivetrain: swpc, but the running robot is differential"), std::string::npos)
      << kind;
  RobotModel three = swpc4;
  three.modules.pop_back();
  const std::string count = model_swap_problem(swpc4, three);
  EXPECT_NE(count.find(std::to_string(swpc4.module_count() - 1) +
                       " modules, but the running "
                       "robot has " +
                       std::to_string(swpc4.module_count())),
            std::string::npos)
      << count;
  RobotModel renamed = docent;
  renamed.name = "other";
  const std::string name = model_swap_problem(docent, renamed);
  EXPECT_NE(name.find("name: 'other', but the running robot is 'docent'"), std::string::npos)
      << name;
}

TEST(ReloadPlan, LiveAndRestartChangesAreReportedTogetherInReferenceOrder) {
  std::string text = shipped_text();
  for (const auto& [from, to] :
       std::vector<std::pair<std::string, std::string>>{{"plugin: raw_eg", "plugin: lsm"},
                                                        {"domain_id: 0 ", "domain_id: 3 "},
                                                        {"rate_hz: 1000", "rate_hz: 250"},
                                                        {"level: info", "level: warn"}}) {
    text.replace(text.find(from), from.size(), to);
  }
  const ReloadPlan plan = plan_for(parse_daemon_config(text, "swiveld.yaml", config_dir));
  EXPECT_TRUE(plan.swap_localization);
  EXPECT_EQ(plan.log_level, "warn");
  EXPECT_EQ(plan.restart, (std::vector<std::string>{"loop.rate_hz", "dds"}));
  EXPECT_EQ(describe_reload({"localization raw_eg -> lsm", "logging.level warn"}, plan.restart),
            "applied localization raw_eg -> lsm, logging.level warn; needs a restart: "
            "loop.rate_hz, dds");
}

}  // namespace
}  // namespace swivel::daemon
