// SPDX-License-Identifier: Apache-2.0
#include "sim_hardware.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "swivel/config/config_error.hpp"
#include "test_support.hpp"

namespace swivel::plugins {
namespace {

class SimHardwareTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / "swivel_sim_hardware_test";
    std::filesystem::create_directories(dir_);
    nominal_ = sim::test::docent();
    nominal_.source_file = (dir_ / "docent.yaml").string();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  PluginContext context(const std::string& params_yaml) {
    PluginContext ctx;
    ctx.params = YAML::Load(params_yaml);
    ctx.config_file = (dir_ / "swiveld.yaml").string();
    ctx.params_path = "hardware.params";
    ctx.config_dir = dir_.string();
    ctx.robot = &nominal_;
    ctx.period_s = 0.001;
    return ctx;
  }

  std::filesystem::path dir_;
  RobotModel nominal_;
};

ActuatorCommand forward_command() {
  ActuatorCommand c;
  c.module_count = 2;
  c.wheel_rate_radps = {4.0, 4.0};
  return c;
}

TEST_F(SimHardwareTest, StepsTheWorldOnTheDaemonsClock) {
  SimHardware hw;
  hw.configure(context("{seed: 3, sensor_noise: false}"));
  HardwareState s;
  ASSERT_EQ(hw.read(1000.0, s), Status::kOk);  // starts the clock
  EXPECT_EQ(s.stamp_s, 1000.0);
  EXPECT_TRUE(s.motion_capture.valid);
  EXPECT_NEAR(s.motion_capture.stamp_s, 1000.0, 1e-9);
  ASSERT_EQ(hw.write(forward_command()), Status::kOk);
  for (int k = 1; k <= 1000; ++k) ASSERT_EQ(hw.read(1000.0 + k * 0.001, s), Status::kOk);
  Pose2 truth;
  ASSERT_TRUE(hw.ground_truth(truth));
  EXPECT_NEAR(truth.x_m, 4.0 * 0.075, 1e-9);
  EXPECT_NEAR(s.wheel_angle_rad[0], 4.0, 2.0 * std::numbers::pi / 4096.0);
}

// A stalled loop must not make the next read run the whole gap in 1 ms substeps on the
// real-time thread: each read advances at most max_substeps_per_read substeps, and the world
// catches up over the following reads.
TEST_F(SimHardwareTest, AStallIsCaughtUpInBoundedSteps) {
  SimHardware hw;
  hw.configure(context("{seed: 3, sensor_noise: false, max_substeps_per_read: 20}"));
  HardwareState s;
  ASSERT_EQ(hw.read(100.0, s), Status::kOk);
  ASSERT_EQ(hw.write(forward_command()), Status::kOk);
  ASSERT_EQ(hw.read(100.001, s), Status::kOk);
  EXPECT_NEAR(hw.sim_time_s(), 0.001, 1e-12);

  // A 2 s stall: one read advances 20 ms of physics and says so in its stamp.
  ASSERT_EQ(hw.read(102.001, s), Status::kOk);
  EXPECT_NEAR(hw.sim_time_s(), 0.021, 1e-9);
  EXPECT_NEAR(s.stamp_s, 100.021, 1e-9);
  EXPECT_NEAR(hw.behind_s(), 1.98, 1e-9);

  // At 1 ms per cycle the world gains 19 ms a read: caught up after 105 more reads.
  double previous = hw.sim_time_s();
  int reads = 0;
  for (int k = 1; hw.behind_s() > 1e-9 && k <= 200; ++k, ++reads) {
    ASSERT_EQ(hw.read(102.001 + k * 0.001, s), Status::kOk);
    EXPECT_LE(hw.sim_time_s() - previous, 0.020 + 1e-9);
    previous = hw.sim_time_s();
  }
  EXPECT_EQ(reads, 105);
  EXPECT_NEAR(s.stamp_s, 102.106, 1e-9);
  // No motion lost: the wheels turned for the whole 2.106 s at 4 rad/s.
  Pose2 truth;
  ASSERT_TRUE(hw.ground_truth(truth));
  EXPECT_NEAR(truth.x_m, 4.0 * 0.075 * 2.106, 1e-6);
}

TEST_F(SimHardwareTest, RejectsNonFiniteCommandsAndBackwardTime) {
  SimHardware hw;
  hw.configure(context("{}"));
  HardwareState s;
  ASSERT_EQ(hw.read(5.0, s), Status::kOk);
  ActuatorCommand bad = forward_command();
  bad.wheel_rate_radps[1] = INFINITY;
  EXPECT_EQ(hw.write(bad), Status::kError);
  EXPECT_STREQ(hw.last_error(), "sim: non-finite actuator setpoint");
  ActuatorCommand wrong = forward_command();
  wrong.module_count = 4;
  EXPECT_EQ(hw.write(wrong), Status::kError);
  EXPECT_EQ(hw.read(4.0, s), Status::kError);
  EXPECT_STREQ(hw.last_error(), "sim: stamp went backwards");
}

TEST_F(SimHardwareTest, TrueModelIsReadRelativeToTheConfigDirectory) {
  std::ofstream(dir_ / "docent_true.yaml")
      << "name: docent\ndrivetrain: differential\n"
         "differential: {wheel_radius_left_m: 0.075, wheel_radius_right_m: 0.0765, "
         "track_width_m: 0.40}\n"
         "sensors:\n  wheel_encoder_counts_per_rev: 4096\n"
         "  gyro: {scale: 1.0, bias_rad_s: 0.0, noise_rad_s: 0.0}\n"
         "effects: {gyro_bias: {bias_rad_s: 0.01}}\n";
  SimHardware hw;
  hw.configure(context("{true_model: docent_true.yaml, motion_capture: false}"));
  HardwareState s;
  ASSERT_EQ(hw.read(0.0, s), Status::kOk);
  EXPECT_FALSE(s.motion_capture.valid);
  ASSERT_EQ(hw.write(forward_command()), Status::kOk);
  for (int k = 1; k <= 100; ++k) ASSERT_EQ(hw.read(k * 0.01, s), Status::kOk);
  Pose2 truth;
  hw.ground_truth(truth);
  EXPECT_GT(truth.yaw_rad, 0.01);  // the right wheel is 2 % larger in the world
  EXPECT_NEAR(s.gyro_wz_radps, 0.01 + 4.0 * (0.0765 - 0.075) / 0.40, 1e-9);
}

TEST_F(SimHardwareTest, ConfigurationErrorsNameTheKey) {
  SimHardware hw;
  try {
    hw.configure(context("{seed: 1, sead: 2}"));
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("sead"), std::string::npos) << e.what();
  }
  try {
    hw.configure(context("{slip: {wheel_std: 2.0}}"));
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("wheel_std"), std::string::npos) << e.what();
  }
  nominal_.effects["gyro_bias"]["bias"] = 1.0;
  try {
    hw.configure(context("{}"));
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("effects.gyro_bias.bias: unknown parameter"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace swivel::plugins
