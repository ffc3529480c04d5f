// SPDX-License-Identifier: Apache-2.0
#include "kalman_localization.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

#include "swivel/config/config_error.hpp"

namespace swivel::plugins {
namespace {

OdometryIncrement step_of(double d_m, double dyaw_rad) {
  OdometryIncrement o;
  o.dt_s = 0.001;
  o.delta = Pose2{d_m, 0.0, dyaw_rad};
  o.twist = Twist2{d_m / o.dt_s, 0.0, dyaw_rad / o.dt_s};
  o.valid = true;
  return o;
}

PluginContext context(const RobotModel& robot, const char* params) {
  PluginContext ctx;
  ctx.robot = &robot;
  ctx.config_file = "swiveld.yaml";
  ctx.params_path = "localization.params";
  ctx.params = YAML::Load(params);
  return ctx;
}

TEST(KalmanLocalization, HandOverKeepsPoseAndCovariance) {
  RobotModel robot;
  KalmanLocalization loc;
  loc.configure(context(robot, "{mode: ekf}"));
  HardwareState readings;
  readings.gyro_valid = true;
  readings.gyro_wz_radps = 0.003;
  for (int i = 0; i < 500; ++i) ASSERT_EQ(loc.update(step_of(3e-4, 1e-4), readings), Status::kOk);
  const double bias_before = loc.ekf().bias_radps();

  PoseEstimate handed;
  handed.pose = Pose2{2.0, -1.5, 2.5};
  handed.has_covariance = true;
  handed.covariance = {0.01, 0.002, 0.0, 0.002, 0.02, 0.0, 0.0, 0.0, 0.003};
  ASSERT_EQ(loc.hand_over(handed), Status::kOk);
  const PoseEstimate out = loc.estimate();
  EXPECT_EQ(out.pose.x_m, 2.0);
  EXPECT_EQ(out.pose.y_m, -1.5);
  EXPECT_NEAR(out.pose.yaw_rad, 2.5, 1e-15);
  for (std::size_t i = 0; i < 9; ++i) EXPECT_EQ(out.covariance[i], handed.covariance[i]);
  EXPECT_EQ(loc.ekf().bias_radps(), bias_before);

  handed.covariance[1] = handed.covariance[3] = 1.0;  // not PSD
  EXPECT_EQ(loc.hand_over(handed), Status::kError);
  EXPECT_STREQ(loc.last_error(), "kalman: handed-over covariance is not positive semi-definite");
}

// From raw_eg or lsm (no covariance) the filter takes on the documented hand-over
// uncertainty, not zero: with zero it would trust the dead-reckoned pose over every fix.
TEST(KalmanLocalization, HandOverWithoutCovarianceTakesTheDefaultUncertainty) {
  RobotModel robot;
  for (const char* mode : {"{mode: ekf}", "{mode: lcakf}"}) {
    SCOPED_TRACE(mode);
    KalmanLocalization loc;
    loc.configure(context(robot, mode));
    PoseEstimate handed;
    handed.pose = {2.0, -1.0, 0.5};
    ASSERT_EQ(loc.hand_over(handed), Status::kOk);
    const PoseEstimate e = loc.estimate();
    ASSERT_TRUE(e.has_covariance);
    EXPECT_NEAR(e.covariance[0], 0.1 * 0.1, 1e-12);
    EXPECT_NEAR(e.covariance[4], 0.1 * 0.1, 1e-12);
    EXPECT_NEAR(e.covariance[8], 0.05 * 0.05, 1e-12);
    EXPECT_DOUBLE_EQ(e.pose.x_m, 2.0);
  }
  KalmanLocalization tuned;
  tuned.configure(context(robot, "{handover_position_sigma_m: 0.3, handover_yaw_sigma_rad: 0.1}"));
  ASSERT_EQ(tuned.hand_over(PoseEstimate{}), Status::kOk);
  EXPECT_NEAR(tuned.estimate().covariance[0], 0.09, 1e-12);
  EXPECT_NEAR(tuned.estimate().covariance[8], 0.01, 1e-12);
}

TEST(KalmanLocalization, MotionCaptureSampleCorrectsPose) {
  RobotModel robot;
  KalmanLocalization loc;
  loc.configure(context(robot, "{initial_position_sigma_m: 0.5, initial_yaw_sigma_rad: 0.2}"));
  HardwareState readings;
  readings.motion_capture.valid = true;
  readings.motion_capture.pose = Pose2{0.3, 0.4, 0.05};
  ASSERT_EQ(loc.update(step_of(0.0, 0.0), readings), Status::kOk);
  const PoseEstimate e = loc.estimate();
  EXPECT_NEAR(e.pose.x_m, 0.3, 1e-3);
  EXPECT_NEAR(e.pose.y_m, 0.4, 1e-3);
  EXPECT_NEAR(e.pose.yaw_rad, 0.05, 1e-3);
  EXPECT_LT(e.covariance[0], 1e-6);
}

TEST(KalmanLocalization, LcakfModeFollowsEgPositions) {
  RobotModel robot;
  KalmanLocalization loc;
  loc.configure(context(robot, "{mode: lcakf, heading_source: encoders}"));
  ASSERT_EQ(loc.config().mode, KalmanMode::kLcakf);
  for (int i = 0; i < 5000; ++i)
    ASSERT_EQ(loc.update(step_of(3e-4, 0.0), HardwareState{}), Status::kOk);
  const PoseEstimate e = loc.estimate();
  EXPECT_NEAR(e.pose.x_m, 1.5, 1e-3);  // constant velocity: no lag once converged
  EXPECT_NEAR(e.pose.y_m, 0.0, 1e-12);
  EXPECT_TRUE(e.has_covariance);
  EXPECT_GT(e.covariance[0], 0.0);
}

TEST(KalmanLocalization, RejectsUnknownKeyAndBadMode) {
  RobotModel robot;
  KalmanLocalization loc;
  try {
    loc.configure(context(robot, "{mode: ekf, gyro_noise: 0.1}"));
    FAIL() << "unknown key accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("localization.params.gyro_noise"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(loc.configure(context(robot, "{mode: ukf}")), ConfigError);
}

}  // namespace
}  // namespace swivel::plugins
