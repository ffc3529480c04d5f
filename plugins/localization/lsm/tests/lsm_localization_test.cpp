// SPDX-License-Identifier: Apache-2.0
#include "lsm_localization.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
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
  // No covariance handed: the E/G's own goes on (0.6 m along x at the default 0.01 m/sqrt(m)).
  ASSERT_TRUE(loc.estimate().has_covariance);
  EXPECT_NEAR(loc.estimate().covariance[0], 0.01 * 0.01 * 0.6, 1e-12);

  handed.has_covariance = true;
  handed.covariance = {0.04, 0.01, 0.0, 0.01, 0.09, 0.0, 0.0, 0.0, 0.01};
  ASSERT_EQ(loc.hand_over(handed), Status::kOk);
  EXPECT_EQ(loc.estimate().covariance, handed.covariance);
  PoseEstimate bad = handed;
  bad.covariance[8] = std::nan("");
  EXPECT_EQ(loc.hand_over(bad), Status::kError);
  EXPECT_STREQ(loc.last_error(),
               "lsm: handed-over covariance is not finite and positive semi-definite");
  EXPECT_EQ(loc.estimate().covariance, handed.covariance);
}

TEST(LsmLocalization, CovarianceCountsTheCompensationShift) {
  RobotModel robot;
  LsmLocalization loc;
  loc.configure(context(robot, "{window_points: 5, heading_source: encoders}"));
  HardwareState readings;
  // A straight run along x whose E/G positions zigzag sideways: the fit moves the output.
  for (int i = 0; i < 2000; ++i) {
    OdometryIncrement o = forward_step(3e-4);
    o.delta.y_m = (i / 40) % 2 == 0 ? 2e-4 : -2e-4;
    ASSERT_EQ(loc.update(o, readings), Status::kOk);
  }
  const PoseEstimate e = loc.estimate();
  const double cx = e.pose.x_m - loc.raw_eg().x_m;
  const double cy = e.pose.y_m - loc.raw_eg().y_m;
  ASSERT_GT(std::abs(cy), 1e-4);
  const auto& eg = loc.eg_covariance().covariance();
  EXPECT_NEAR(e.covariance[0], eg(0, 0) + cx * cx, 1e-15);
  EXPECT_NEAR(e.covariance[1], eg(0, 1) + cx * cy, 1e-15);
  EXPECT_NEAR(e.covariance[4], eg(1, 1) + cy * cy, 1e-15);
  EXPECT_EQ(e.covariance[8], eg(2, 2));
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
