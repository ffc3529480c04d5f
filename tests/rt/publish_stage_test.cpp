// SPDX-License-Identifier: Apache-2.0
// PublishStage: the cycle's state reaches latest() with the drivetrain's module states and the
// hardware's ground truth; a paused cycle publishes a stopped robot; run samples follow.

#include "swivel/rt/publish_stage.hpp"

#include <gtest/gtest.h>

#include "fake_plugins.hpp"

namespace swivel::rt {
namespace {

using test::FakeDrivetrain;
using test::FakeHardware;

TEST(PublishStage, TheCyclesStateReachesLatestWithModulesAndTruth) {
  PublishStage stage(0.001, 0.001);
  FakeHardware hardware;
  FakeDrivetrain drivetrain;
  HardwareState reading;
  reading.module_count = 2;
  reading.wheel_angle_rad[1] = 3.0;
  reading.gyro_valid = true;
  reading.gyro_wz_radps = 0.2;
  stage.state().estimate.pose.x_m = 1.5;  // another stage's share
  stage.publish(CycleReport{2.0, 42, {0.1, 0.0, 0.0}, &reading, true, 2, true}, drivetrain,
                hardware);
  const StateSnapshot out = stage.latest();
  EXPECT_EQ(out.cycle, 1U);
  EXPECT_EQ(out.stamp_s, 2.0);
  EXPECT_EQ(out.ros_stamp_ns, 42);
  EXPECT_EQ(out.command_twist.vx_mps, 0.1);
  EXPECT_EQ(out.gyro_wz_radps, 0.2);
  EXPECT_EQ(out.wheel_angle_rad[1], 3.0);
  EXPECT_EQ(out.estimate.pose.x_m, 1.5);
  EXPECT_EQ(out.module_count, 2U);
  EXPECT_TRUE(out.has_truth);
  EXPECT_TRUE(out.stopping);
  RunSample sample;
  ASSERT_TRUE(stage.run_samples().take(sample));
  EXPECT_EQ(sample.cycle, 1U);

  stage.publish(CycleReport{2.001, 43, {}, &reading, false, 2, false}, drivetrain, hardware);
  EXPECT_EQ(stage.latest().gyro_wz_radps, 0.0);  // no usable reading: no gyro
}

TEST(PublishStage, APausedCyclePublishesAStoppedRobot) {
  PublishStage stage(0.0, 0.001);
  stage.state().odometry_twist = {0.3, 0.0, 0.1};
  stage.state().has_joint_rates = true;
  stage.state().command_twist = {0.3, 0.0, 0.0};
  stage.write();
  EXPECT_EQ(stage.latest().odometry_twist.vx_mps, 0.3);
  stage.publish_paused(5.0, 7);
  const StateSnapshot out = stage.latest();
  EXPECT_EQ(out.cycle, 1U);
  EXPECT_EQ(out.stamp_s, 5.0);
  EXPECT_EQ(out.odometry_twist.vx_mps, 0.0);
  EXPECT_EQ(out.command_twist.vx_mps, 0.0);
  EXPECT_FALSE(out.has_joint_rates);
  RunSample sample;
  EXPECT_FALSE(stage.run_samples().take(sample));
}

}  // namespace
}  // namespace swivel::rt
