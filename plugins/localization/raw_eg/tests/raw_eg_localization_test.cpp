// SPDX-License-Identifier: Apache-2.0
#include "raw_eg_localization.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

#include "swivel/config/config_error.hpp"

namespace swivel::plugins {
namespace {

OdometryIncrement straight(double d_m, double dyaw_rad) {
  OdometryIncrement o;
  o.dt_s = 0.001;
  o.delta = Pose2{d_m, 0.0, dyaw_rad};
  o.valid = true;
  return o;
}

PluginContext context(RobotModel& robot, const char* params) {
  PluginContext ctx;
  ctx.robot = &robot;
  ctx.config_file = "swiveld.yaml";
  ctx.params_path = "localization.params";
  ctx.params = YAML::Load(params);
  return ctx;
}

TEST(RawEgLocalization, EncoderModeIgnoresGyro) {
  RobotModel robot;
  RawEgLocalization loc;
  loc.configure(context(robot, "{heading_source: encoders}"));
  HardwareState readings;
  readings.gyro_valid = true;
  readings.gyro_wz_radps = 5.0;
  ASSERT_EQ(loc.update(straight(0.001, 0.002), readings), Status::kOk);
  EXPECT_NEAR(loc.estimate().pose.yaw_rad, 0.002, 1e-15);
  // The encoder heading's noise: 0.05^2 per rad turned and 0.01^2 per m (the defaults).
  ASSERT_TRUE(loc.estimate().has_covariance);
  EXPECT_NEAR(loc.estimate().covariance[8], 0.05 * 0.05 * 0.002 + 0.01 * 0.01 * 0.001, 1e-15);
}

TEST(RawEgLocalization, NoiseModelComesFromParamsWithTheGyroNoiseFromTheModel) {
  RobotModel robot;
  robot.sensors.gyro.noise_rad_s = 0.004;
  robot.sensors.gyro.scale = 2.0;
  RawEgLocalization loc;
  loc.configure(context(robot,
                        "{along_track_noise_m_per_sqrt_m: 0.03, cross_track_noise_m_per_sqrt_m: "
                        "0.001, gyro_bias_sigma_radps: 0.002, "
                        "bias_random_walk_radps_per_sqrt_s: 0.0}"));
  const localization::EgNoise& n = loc.covariance().noise();
  EXPECT_EQ(n.along_track_m_per_sqrt_m, 0.03);
  EXPECT_EQ(n.cross_track_m_per_sqrt_m, 0.001);
  EXPECT_EQ(n.rotation_rad_per_sqrt_rad, 0.05);
  EXPECT_EQ(n.yaw_rad_per_sqrt_m, 0.01);
  EXPECT_EQ(n.gyro_noise_radps, 0.002);  // sensors.gyro.noise_rad_s / scale
  EXPECT_EQ(n.gyro_bias_sigma_radps, 0.002);
  EXPECT_EQ(n.bias_walk_radps_per_sqrt_s, 0.0);
  HardwareState readings;
  readings.gyro_valid = true;
  for (int k = 0; k < 1000; ++k) ASSERT_EQ(loc.update(straight(0.001, 0.0), readings), Status::kOk);
  const PoseEstimate e = loc.estimate();
  EXPECT_NEAR(e.covariance[0], 0.03 * 0.03 * 1.0, 1e-9);
  // 1 s of gyro noise and the residual bias: 1000 (0.002 * 0.001)^2 + (0.002 * 1)^2.
  EXPECT_NEAR(e.covariance[8], 1000 * 4e-12 + 4e-6, 1e-12);
}

TEST(RawEgLocalization, HandOverTakesAValidCovarianceAndKeepsItsOwnWithoutOne) {
  RawEgLocalization loc;
  HardwareState readings;
  for (int k = 0; k < 100; ++k) ASSERT_EQ(loc.update(straight(0.01, 0.0), readings), Status::kOk);
  const PoseEstimate own = loc.estimate();
  ASSERT_GT(own.covariance[0], 0.0);

  PoseEstimate without;
  without.pose = Pose2{1.0, 2.0, 0.3};
  ASSERT_EQ(loc.hand_over(without), Status::kOk);
  EXPECT_EQ(loc.estimate().covariance, own.covariance);

  PoseEstimate with = without;
  with.has_covariance = true;
  with.covariance = {0.04, 0.0, 0.0, 0.0, 0.09, 0.001, 0.0, 0.001, 0.01};
  ASSERT_EQ(loc.hand_over(with), Status::kOk);
  EXPECT_EQ(loc.estimate().covariance, with.covariance);
  EXPECT_EQ(loc.estimate().pose.y_m, 2.0);

  PoseEstimate bad = with;
  bad.covariance[0] = -1.0;
  EXPECT_EQ(loc.hand_over(bad), Status::kError);
  EXPECT_STREQ(loc.last_error(),
               "raw_eg: handed-over covariance is not finite and positive semi-definite");
  EXPECT_EQ(loc.estimate().covariance, with.covariance);  // nothing changed
}

TEST(RawEgLocalization, GyroModeCorrectsWithNominalGyroModel) {
  RobotModel robot;
  robot.sensors.gyro.bias_rad_s = 0.5;
  RawEgLocalization loc;
  loc.configure(context(robot, "{}"));
  HardwareState readings;
  readings.gyro_valid = true;
  readings.gyro_wz_radps = 1.5;
  ASSERT_EQ(loc.update(straight(0.001, 0.0), readings), Status::kOk);
  EXPECT_NEAR(loc.estimate().pose.yaw_rad, 1.0 * 0.001, 1e-15);
}

TEST(RawEgLocalization, RejectsAGyroScaleOfZeroNamingTheRobotModel) {
  RobotModel robot;
  robot.source_file = "robots/docent.yaml";
  robot.sensors.gyro.scale = 0.0;
  RawEgLocalization loc;
  try {
    loc.configure(context(robot, "{}"));
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "robots/docent.yaml: sensors.gyro: expected a finite non-zero scale and a "
                 "finite bias");
  }
}

TEST(RawEgLocalization, HandOverKeepsPoseAndInvalidOdometryIsIgnored) {
  RawEgLocalization loc;
  PoseEstimate handed;
  handed.pose = Pose2{3.0, -1.0, 0.7};
  ASSERT_EQ(loc.hand_over(handed), Status::kOk);
  OdometryIncrement invalid = straight(1.0, 1.0);
  invalid.valid = false;
  ASSERT_EQ(loc.update(invalid, HardwareState{}), Status::kOk);
  EXPECT_EQ(loc.estimate().pose.x_m, 3.0);
  EXPECT_EQ(loc.estimate().pose.y_m, -1.0);
  EXPECT_EQ(loc.estimate().pose.yaw_rad, 0.7);
}

TEST(RawEgLocalization, RejectsUnknownKeyAndBadChoice) {
  RobotModel robot;
  RawEgLocalization loc;
  EXPECT_THROW(loc.configure(context(robot, "{heading: gyro}")), ConfigError);
  try {
    loc.configure(context(robot, "{heading_source: compass}"));
    FAIL() << "bad choice accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("localization.params.heading_source"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace swivel::plugins
