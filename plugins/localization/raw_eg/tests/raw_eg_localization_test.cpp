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
  EXPECT_FALSE(loc.estimate().has_covariance);
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
