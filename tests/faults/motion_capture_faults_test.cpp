// SPDX-License-Identifier: Apache-2.0
// Rows of docs/faults.md for the motion-capture stream: gaps, and non-finite samples.
// Samples come through the loop's motion-capture input (as the DDS bridge delivers them),
// taken from the simulated world's true pose at 100 Hz.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fault_rig.hpp"

namespace swivel::faults {
namespace {

double position_variance(const StateSnapshot& s) {
  return s.estimate.covariance[0] + s.estimate.covariance[4];
}

// Drives a circle for `cycles`, pushing a true-pose sample every 10 cycles unless `gap`.
void drive_with_fixes(FaultRig& rig, int cycles, bool gap) {
  for (int i = 0; i < cycles; ++i) {
    if (i % 10 == 0) {
      rig.command(0.3, 0.0, 0.3);
      if (!gap) {
        MotionCaptureSample fix;
        fix.valid = true;
        fix.stamp_s = rig.t_s;
        fix.pose = rig.state().truth;
        ASSERT_TRUE(rig.loop->push_motion_capture(fix));
      }
    }
    rig.step();
  }
}

TEST(MotionCaptureFaults, KalmanKeepsAValidEstimateThroughAGap) {
  RigOptions options;
  options.localization = "kalman";
  options.localization_params = "{initial_position_sigma_m: 0.01}";
  FaultRig rig(options);
  drive_with_fixes(rig, 1000, false);
  const StateSnapshot fixed = rig.state();
  ASSERT_TRUE(fixed.estimate.has_covariance);
  const double fixed_variance = position_variance(fixed);
  ASSERT_LT(fixed_variance, 1e-6);

  // A 2 s gap: dead reckoning carries on, the uncertainty grows every cycle it moves.
  double previous_variance = fixed_variance;
  for (int k = 0; k < 20; ++k) {
    drive_with_fixes(rig, 100, true);
    const StateSnapshot s = rig.state();
    ASSERT_EQ(s.mode, LoopMode::kVelocity);
    ASSERT_TRUE(std::isfinite(s.estimate.pose.x_m) && std::isfinite(s.estimate.pose.y_m));
    ASSERT_GT(position_variance(s), previous_variance);
    previous_variance = position_variance(s);
    ASSERT_LT(distance_m(s.estimate.pose, s.truth), 0.01);
  }
  EXPECT_GT(previous_variance, 10.0 * fixed_variance);

  // Fixes again: the estimate is pulled back and the uncertainty collapses.
  drive_with_fixes(rig, 100, false);
  const StateSnapshot back = rig.state();
  EXPECT_LT(position_variance(back), 2.0 * fixed_variance);
  EXPECT_LT(distance_m(back.estimate.pose, back.truth), 0.002);
  EXPECT_EQ(back.fault_count, 0U);
  EXPECT_EQ(back.cycle, 3100U);
}

TEST(MotionCaptureFaults, RawEgDeadReckonsThroughAGapWithoutAJump) {
  FaultRig rig;  // raw_eg ignores fixes: a gap must change nothing
  drive_with_fixes(rig, 500, false);
  Pose2 previous = rig.state().estimate.pose;
  for (int i = 0; i < 2000; ++i) {
    drive_with_fixes(rig, 1, i >= 500 && i < 1500);
    const StateSnapshot s = rig.state();
    // 0.3 mm per cycle, give or take an encoder count: a jump would be far more.
    ASSERT_LT(distance_m(s.estimate.pose, previous), 0.001) << "cycle " << i;
    previous = s.estimate.pose;
  }
  EXPECT_LT(distance_m(rig.state().estimate.pose, rig.state().truth), 0.01);
  EXPECT_EQ(rig.state().fault_count, 0U);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
}

TEST(MotionCaptureFaults, NonFiniteSampleIsDroppedWithoutAFault) {
  RigOptions options;
  options.localization = "kalman";
  FaultRig rig(options);
  drive_with_fixes(rig, 200, false);
  const StateSnapshot before = rig.state();
  MotionCaptureSample bad;
  bad.valid = true;
  bad.stamp_s = rig.t_s;
  bad.pose = {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
  ASSERT_TRUE(rig.loop->push_motion_capture(bad));
  rig.command(0.3, 0.0, 0.3);
  rig.step();
  const StateSnapshot after = rig.state();
  EXPECT_EQ(after.mode, LoopMode::kVelocity);
  EXPECT_EQ(after.fault_count, before.fault_count);
  EXPECT_TRUE(std::isfinite(after.estimate.pose.x_m));
  EXPECT_LT(distance_m(after.estimate.pose, after.truth), 0.002);
  EXPECT_NE(rig.log().find("non-finite motion-capture sample dropped"), std::string::npos);
}

}  // namespace
}  // namespace swivel::faults
