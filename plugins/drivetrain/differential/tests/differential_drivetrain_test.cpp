// SPDX-License-Identifier: Apache-2.0
#include "differential_drivetrain.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "swivel/config/config_error.hpp"

namespace swivel::plugins {
namespace {

constexpr DifferentialParams kDocent{0.075, 0.075, 0.40};

HardwareState reading(double stamp_s, double left_rad, double right_rad) {
  HardwareState s;
  s.stamp_s = stamp_s;
  s.module_count = 2;
  s.wheel_angle_rad[0] = left_rad;
  s.wheel_angle_rad[1] = right_rad;
  return s;
}

TEST(DifferentialDrivetrain, ForwardGivesArcAndMeanTwist) {
  DifferentialDrivetrain dt;
  dt.configure(kDocent, 20.0);
  // 10 ms at vx = 0.3 m/s, wz = 0.5 rad/s: wheel rates 0.2/0.075 and 0.4/0.075 rad/s.
  const double t = 0.01;
  OdometryIncrement odo;
  ASSERT_EQ(dt.forward(reading(1.0, 5.0, 7.0),
                       reading(1.0 + t, 5.0 + t * 0.2 / 0.075, 7.0 + t * 0.4 / 0.075), odo),
            Status::kOk);
  ASSERT_TRUE(odo.valid);
  EXPECT_NEAR(odo.dt_s, t, 1e-15);
  EXPECT_NEAR(odo.twist.vx_mps, 0.3, 1e-9);
  EXPECT_EQ(odo.twist.vy_mps, 0.0);
  EXPECT_NEAR(odo.twist.wz_radps, 0.5, 1e-9);
  const double a = 0.5 * t;
  EXPECT_NEAR(odo.delta.x_m, 0.3 * std::sin(a) / 0.5, 1e-12);
  EXPECT_NEAR(odo.delta.y_m, 0.3 * (1.0 - std::cos(a)) / 0.5, 1e-12);
  EXPECT_NEAR(odo.delta.yaw_rad, a, 1e-12);

  std::array<ModuleState, 2> states{};
  dt.module_states(states);
  EXPECT_NEAR(states[0].wheel_rate_meas_radps, 0.2 / 0.075, 1e-9);
  EXPECT_NEAR(states[1].wheel_rate_meas_radps, 0.4 / 0.075, 1e-9);
}

TEST(DifferentialDrivetrain, ImplausibleIncrementIsRejectedNamingTheWheel) {
  // Limit 20 rad/s, factor 3, margin 0.01 rad: over 10 ms a wheel may turn 0.61 rad.
  DifferentialDrivetrain dt;
  dt.configure(kDocent, 20.0, 3.0, 0.01);
  EXPECT_DOUBLE_EQ(dt.plausible_wheel_rate_radps(), 60.0);
  OdometryIncrement odo;
  EXPECT_EQ(dt.forward(reading(1.0, 0.0, 0.0), reading(1.01, 0.6, -0.6), odo), Status::kOk);
  EXPECT_EQ(dt.forward(reading(1.0, 0.0, 0.0), reading(1.01, 0.0, -0.62), odo), Status::kError);
  EXPECT_STREQ(dt.last_error(), "differential: right wheel rate implausible (encoder jump)");
  EXPECT_FALSE(odo.valid);
  EXPECT_EQ(dt.forward(reading(1.0, 0.0, 0.0), reading(1.01, 50.0, 0.0), odo), Status::kError);
  EXPECT_STREQ(dt.last_error(), "differential: left wheel rate implausible (encoder jump)");
  std::array<ModuleState, 2> states{};
  dt.module_states(states);
  EXPECT_NEAR(states[0].wheel_rate_meas_radps, 5000.0, 1e-9);
  EXPECT_THROW(dt.configure(kDocent, 20.0, 0.5, 0.01), ConfigError);
}

TEST(DifferentialDrivetrain, InverseScalesTwistToKeepCurvature) {
  DifferentialDrivetrain dt;
  dt.configure(kDocent, 20.0);
  ActuatorCommand cmd;
  Twist2 applied;
  ASSERT_EQ(dt.inverse(Twist2{2.0, 0.7, 1.0}, reading(0.0, 0.0, 0.0), 0.001, cmd, applied),
            Status::kOk);
  EXPECT_EQ(cmd.module_count, 2U);
  EXPECT_EQ(cmd.mode[0], ModuleDriveMode::kVelocity);
  EXPECT_NEAR(cmd.wheel_rate_radps[1], 20.0, 1e-12);           // the faster wheel at its limit
  EXPECT_NEAR(applied.wz_radps / applied.vx_mps, 0.5, 1e-12);  // curvature kept
  EXPECT_EQ(applied.vy_mps, 0.0);  // non-holonomic: lateral command dropped
  EXPECT_NEAR(cmd.wheel_rate_radps[0], (applied.vx_mps - 0.2 * applied.wz_radps) / 0.075, 1e-12);
  std::array<ModuleState, 2> states{};
  dt.module_states(states);
  EXPECT_NEAR(states[1].wheel_rate_cmd_radps, 20.0, 1e-12);
}

TEST(DifferentialDrivetrain, InverseWithinLimitsIsUnscaled) {
  DifferentialDrivetrain dt;
  dt.configure(kDocent, 20.0);
  ActuatorCommand cmd;
  Twist2 applied;
  ASSERT_EQ(dt.inverse(Twist2{0.3, 0.0, 0.0}, reading(0.0, 0.0, 0.0), 0.001, cmd, applied),
            Status::kOk);
  EXPECT_NEAR(applied.vx_mps, 0.3, 1e-15);
  EXPECT_NEAR(cmd.wheel_rate_radps[0], 4.0, 1e-12);
  EXPECT_NEAR(cmd.wheel_rate_radps[1], 4.0, 1e-12);
}

TEST(DifferentialDrivetrain, RejectsNonFiniteInputsWithZeroOutput) {
  DifferentialDrivetrain dt;
  dt.configure(kDocent, 20.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ActuatorCommand cmd;
  Twist2 applied{1.0, 1.0, 1.0};
  EXPECT_EQ(dt.inverse(Twist2{nan, 0.0, 0.0}, reading(0.0, 0.0, 0.0), 0.001, cmd, applied),
            Status::kError);
  EXPECT_STREQ(dt.last_error(), "differential: non-finite velocity command");
  EXPECT_EQ(cmd.wheel_rate_radps[0], 0.0);
  EXPECT_EQ(applied.vx_mps, 0.0);

  OdometryIncrement odo;
  EXPECT_EQ(dt.forward(reading(0.0, 0.0, 0.0), reading(0.001, nan, 0.0), odo), Status::kError);
  EXPECT_STREQ(dt.last_error(), "differential: non-finite wheel angle");
  EXPECT_FALSE(odo.valid);
  EXPECT_EQ(dt.forward(reading(0.0, 0.0, 0.0), reading(0.0, 0.0, 0.0), odo), Status::kError);
  EXPECT_STREQ(dt.last_error(), "differential: timestamps not increasing");
}

TEST(DifferentialDrivetrain, ConfigureReadsLimitAndRejectsUnknownKey) {
  RobotModel robot;
  robot.source_file = "docent.yaml";
  PluginContext ctx;
  ctx.robot = &robot;
  ctx.config_file = "swiveld.yaml";
  ctx.params_path = "drivetrain.params";
  ctx.params = YAML::Load("{max_wheel_rate_radps: 12.5}");
  DifferentialDrivetrain dt;
  dt.configure(ctx);
  EXPECT_EQ(dt.max_wheel_rate_radps(), 12.5);

  ctx.params = YAML::Load("{max_wheel_rate: 12.5}");
  try {
    dt.configure(ctx);
    FAIL() << "unknown key accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("drivetrain.params.max_wheel_rate"), std::string::npos)
        << e.what();
  }

  robot.differential.track_width_m = 0.0;
  ctx.params = YAML::Node();
  try {
    dt.configure(ctx);
    FAIL() << "zero track width accepted";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "docent.yaml: differential.track_width_m: expected a positive number");
  }
}

}  // namespace
}  // namespace swivel::plugins
