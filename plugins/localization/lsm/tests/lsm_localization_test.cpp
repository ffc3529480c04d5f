#include "lsm_localization.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

#include "swivel/config/config_error.hpp"

namespace swivel::plugins {
namespace {

PluginContext context(const RobotModel& robot, const char* params) {
  PluginContext ctx;
  ctx.robot = &robot;
  ctx.config_file = "swiveld.yaml";
  ctx.params_path = "localization.params";
  ctx.params = YAML::Load(params);
  return ctx;
}

OdometryIncrement forward_step(double d_m) {
  OdometryIncrement o;
  o.dt_s = 0.001;
  o.delta = Pose2{d_m, 0.0, 0.0};
  o.valid = true;
  return o;
}

TEST(LsmLocalization, HandOverInTheMiddleOfARunKeepsPose) {
  RobotModel robot;
  LsmLocalization loc;
  loc.configure(context(robot, "{window_points: 5, heading_source: encoders}"));
  HardwareState readings;
  for (int i = 0; i < 2000; ++i) ASSERT_EQ(loc.update(forward_step(3e-4), readings), Status::kOk);
  EXPECT_EQ(loc.lsm().size(), 5U);
  PoseEstimate handed;
  handed.pose = Pose2{4.0, 6.0, -0.3};
  ASSERT_EQ(loc.hand_over(handed), Status::kOk);
  const Pose2 out = loc.estimate().pose;
  EXPECT_EQ(out.x_m, 4.0);
  EXPECT_EQ(out.y_m, 6.0);
  EXPECT_NEAR(out.yaw_rad, -0.3, 1e-15);
  EXPECT_FALSE(loc.estimate().has_covariance);
}

TEST(LsmLocalization, ReadsParamsAndRejectsUnknownKey) {
  RobotModel robot;
  LsmLocalization loc;
  loc.configure(context(robot, "{mode: heading_aligned, sample_period_s: 0.05}"));
  EXPECT_EQ(loc.lsm().config().mode, localization::LsmMode::kHeadingAligned);
  EXPECT_EQ(loc.lsm().config().sample_distance_m, 0.0);
  EXPECT_EQ(loc.lsm().config().sample_period_s, 0.05);
  try {
    loc.configure(context(robot, "{window: 10}"));
    FAIL() << "unknown key accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("localization.params.window"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(loc.configure(context(robot, "{window_points: 100}")), ConfigError);
}

}  // namespace
}  // namespace swivel::plugins
