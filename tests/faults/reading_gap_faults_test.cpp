// SPDX-License-Identifier: Apache-2.0
// Rows of docs/faults.md for the odometry while the hardware gives no readings: a 0.5 s stall
// of the sim at 0.3 m/s with the controlled stop braking at 1 m/s^2, so that the robot is
// still moving for most of the gap (it travels v^2 / 2a = 0.045 m meanwhile).

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "fault_rig.hpp"

namespace swivel::faults {
namespace {

constexpr double kVxMps = 0.3;
constexpr double kStopMps2 = 1.0;
constexpr double kStallS = 0.5;

std::vector<StateSnapshot> drive_through_a_stall(FaultRig& rig, int cycles_after) {
  rig.drive(kVxMps, 0.0, 0.0, 1000);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.inject("stall", kStallS), 0);
  std::vector<StateSnapshot> states{rig.state()};
  const int cycles = static_cast<int>(std::lround(kStallS / FaultRig::kDtS)) + cycles_after;
  for (int i = 0; i < cycles; ++i) {
    rig.step();
    states.push_back(rig.state());
  }
  return states;
}

RigOptions braking_rig(const std::string& localization) {
  RigOptions options;
  options.localization = localization;
  options.stop_linear_deceleration_mps2 = kStopMps2;
  return options;
}

double position_variance(const StateSnapshot& s) {
  return s.estimate.covariance[0] + s.estimate.covariance[4];
}

void expect_honest_odometry_through_a_stall(const std::string& localization) {
  SCOPED_TRACE(localization);
  FaultRig rig(braking_rig(localization));
  const std::vector<StateSnapshot> states = drive_through_a_stall(rig, 300);
  const StateSnapshot& before = states.front();
  ASSERT_TRUE(before.has_twist_covariance);
  ASSERT_TRUE(before.estimate.has_covariance);

  // The gap: every cycle without a reading, up to the first answered read.
  std::size_t first = 1;
  std::size_t resumed = first;
  while (resumed < states.size() && states[resumed].fault == FaultCode::kHardwareError &&
         !states[resumed].has_joint_rates) {
    ++resumed;
  }
  ASSERT_EQ(states[first].fault, FaultCode::kHardwareError);
  ASSERT_LT(resumed, states.size()) << "readings never resumed";
  ASSERT_GT(resumed - first, 400U) << "the stall was shorter than planned";

  double previous_twist_variance = before.twist_covariance[0];
  double previous_pose_variance = position_variance(before);
  for (std::size_t i = first; i + 1 < resumed; ++i) {
    const StateSnapshot& s = states[i];
    SCOPED_TRACE("gap cycle " + std::to_string(i));
    // The twist is the controlled stop's, with a variance that only grows.
    EXPECT_NEAR(s.odometry_twist.vx_mps, s.command_twist.vx_mps, 1e-12);
    ASSERT_TRUE(s.has_twist_covariance);
    EXPECT_GE(s.twist_covariance[0], previous_twist_variance);
    EXPECT_GE(position_variance(s), previous_pose_variance);
    previous_twist_variance = s.twist_covariance[0];
    previous_pose_variance = position_variance(s);
  }
  // Still braking in the gap's first cycles: not "v = 0, certain".
  EXPECT_GT(states[first].odometry_twist.vx_mps, 0.25);
  const StateSnapshot& gap_end = states[resumed - 1];
  EXPECT_GT(gap_end.twist_covariance[0], 100.0 * before.twist_covariance[0]);
  // sigma at the end of the gap covers the whole of the speed the robot might have kept.
  EXPECT_GE(std::sqrt(gap_end.twist_covariance[0]), kVxMps);
  EXPECT_GT(position_variance(gap_end), position_variance(before) + 1e-4);

  // The pose moves on continuously through the gap and at its end: no step beyond one
  // cycle's travel at the speed driven.
  double largest_step_m = 0.0;
  for (std::size_t i = 1; i < states.size(); ++i) {
    largest_step_m =
        std::max(largest_step_m, distance_m(states[i].estimate.pose, states[i - 1].estimate.pose));
  }
  EXPECT_LT(largest_step_m, 1.5 * kVxMps * FaultRig::kDtS);
  // The dead reckoning followed the braking robot: v^2 / 2a travelled in the gap.
  const double travelled_m = distance_m(gap_end.estimate.pose, before.estimate.pose);
  EXPECT_NEAR(travelled_m, kVxMps * kVxMps / (2.0 * kStopMps2), 0.005);

  // On resume the covariance was widened, not reset, and it covers the estimate's error.
  const StateSnapshot& after = states[resumed];
  EXPECT_GE(position_variance(after), position_variance(gap_end));
  const StateSnapshot& at_rest = states.back();
  ASSERT_EQ(at_rest.mode, LoopMode::kSafeStop);
  ASSERT_TRUE(at_rest.has_truth);
  EXPECT_LE(distance_m(at_rest.estimate.pose, at_rest.truth),
            3.0 * std::sqrt(position_variance(at_rest)));
  // At rest after the gap, the twist is measured again: zero within its own uncertainty (a fit
  // across the gap would report the braking as motion with a tiny variance).
  ASSERT_TRUE(at_rest.has_joint_rates);
  ASSERT_TRUE(at_rest.has_twist_covariance);
  EXPECT_LE(std::abs(at_rest.odometry_twist.vx_mps),
            3.0 * std::sqrt(at_rest.twist_covariance[0]) + 1e-9);
  EXPECT_NE(rig.log().find("readings resumed: pose kept"), std::string::npos) << rig.log();
}

TEST(ReadingGapFaults, RawEgOdometryFollowsTheStopAndResumesWithoutAJump) {
  expect_honest_odometry_through_a_stall("raw_eg");
}

TEST(ReadingGapFaults, KalmanOdometryFollowsTheStopAndResumesWithoutAJump) {
  expect_honest_odometry_through_a_stall("kalman");
}

// A localization that refuses the dead-reckoned pose keeps its own and takes the measured
// increment over the gap, as before: a logged jump rather than a fault.
TEST(ReadingGapFaults, ARefusedHandOverFallsBackToTheMeasuredIncrement) {
  RigOptions options = braking_rig("refuses_hand_over");
  FaultRig rig(options);
  const std::vector<StateSnapshot> states = drive_through_a_stall(rig, 50);
  EXPECT_EQ(states.back().fault, FaultCode::kHardwareError);
  EXPECT_NE(rig.log().find("readings resumed: the localization refused the dead-reckoned pose"),
            std::string::npos)
      << rig.log();
  ASSERT_TRUE(states.back().has_truth);
  EXPECT_LT(distance_m(states.back().estimate.pose, states.back().truth), 0.005);
}

}  // namespace
}  // namespace swivel::faults
