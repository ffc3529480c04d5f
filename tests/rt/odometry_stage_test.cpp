// SPDX-License-Identifier: Apache-2.0
// OdometryStage and SwapStage: the cycle's increment reaches the localization and the
// snapshot; a failing drivetrain or localization, or a non-finite estimate, is its latched
// fault; a gap in the readings dead-reckons and hands the estimate over when they resume. A
// hot swap is taken or rolled back at the boundary, one with a drivetrain only at rest.

#include "swivel/rt/odometry_stage.hpp"

#include <gtest/gtest.h>

#include <string>

#include "fake_plugins.hpp"
#include "swivel/rt/swap_stage.hpp"

namespace swivel::rt {
namespace {

using test::FakeDrivetrain;
using test::FakeHardware;
using test::FakeLocalization;

constexpr double kDtS = 0.001;

TwistWindowOptions window() {
  TwistWindowOptions o;
  o.readings = 3;
  return o;
}

// The stages side by side as the loop holds them; the padding does not matter in a test.
// NOLINTNEXTLINE(clang-analyzer-optin.performance.Padding)
struct Rig {
  RtLog log;
  LoopEvents events{log};
  PluginGuard guard;
  ExternalSensorStage sensors{ExternalSensorOptions{}};
  HardwareReadStage read;
  OdometryStage stage{OdometryCheckOptions{}, window()};
  FakeHardware hardware;
  FakeDrivetrain drivetrain;
  FakeLocalization localization;
  StateSnapshot published;
  double t_s = 1.0;

  // One cycle: read, odometry, publish; the wheels turn at `rate_radps` (both).
  OdometryOutcome cycle(double rate_radps) {
    t_s += kDtS;
    events.begin_cycle(published.cycle);
    const ReadOutcome r = read.read(t_s, hardware, sensors, guard, events);
    const OdometryOutcome out = stage.update(t_s, read, r.ok, published, t_s - kDtS, drivetrain,
                                             localization, guard, events);
    ActuatorCommand setpoints;
    setpoints.module_count = 2;
    setpoints.wheel_rate_radps = {rate_radps, rate_radps};
    (void)hardware.write(setpoints);
    stage.advance(Twist2{rate_radps * test::kFakeWheelRadiusM, 0.0, 0.0}, t_s);
    read.end_cycle(r.ok);
    stage.publish(out, localization, published);
    ++published.cycle;
    return out;
  }
};

TEST(OdometryStage, TheIncrementMovesTheEstimateAndTheTwistIsPublished) {
  Rig rig;
  EXPECT_FALSE(rig.cycle(10.0).odometry.valid);  // no previous reading yet
  for (int k = 0; k < 10; ++k) rig.cycle(10.0);
  const OdometryOutcome out = rig.cycle(10.0);
  ASSERT_TRUE(out.odometry.valid);
  EXPECT_TRUE(out.twist_ok);
  EXPECT_NEAR(rig.published.odometry_twist.vx_mps, 1.0, 1e-9);  // 10 rad/s on a 0.1 m wheel
  EXPECT_TRUE(rig.published.has_joint_rates);
  EXPECT_GT(rig.published.estimate.pose.x_m, 0.009);
  EXPECT_EQ(rig.localization.updates.load(), 11U);
  EXPECT_EQ(rig.events.fault_count(), 0U);
}

TEST(OdometryStage, AFailingDrivetrainOrLocalizationIsItsFault) {
  Rig rig;
  rig.cycle(0.0);
  rig.drivetrain.fail_forward = true;
  const OdometryOutcome out = rig.cycle(0.0);
  EXPECT_FALSE(out.twist_ok);
  EXPECT_EQ(rig.events.latched(), FaultCode::kDrivetrainError);
  rig.events.clear_latched(rig.t_s);
  rig.drivetrain.fail_forward = false;
  rig.localization.throw_in_update = true;
  rig.cycle(0.0);
  EXPECT_EQ(rig.events.latched(), FaultCode::kLocalizationError);
  EXPECT_EQ(std::string(rig.events.latched_detail().data()),
            "plugin threw std::runtime_error: fake localization threw");
  rig.events.clear_latched(rig.t_s);
  rig.localization.throw_in_update = false;
  rig.localization.nan_covariance = true;
  rig.cycle(0.0);
  EXPECT_STREQ(rig.events.latched_detail().data(), "non-finite pose covariance");
  EXPECT_FALSE(rig.published.estimate.has_covariance);  // published as none
}

TEST(OdometryStage, AGapDeadReckonsAndTheEstimateIsHandedOverWhenReadingsResume) {
  Rig rig;
  for (int k = 0; k < 5; ++k) rig.cycle(10.0);
  rig.hardware.fail_read = true;
  for (int k = 0; k < 5; ++k) rig.cycle(10.0);
  EXPECT_EQ(rig.events.latched(), FaultCode::kHardwareError);
  EXPECT_EQ(rig.localization.hand_overs.load(), 0U);
  const double reckoned_x_m = rig.published.estimate.pose.x_m;
  EXPECT_GT(reckoned_x_m, 0.004);  // moved on with the applied twist
  rig.hardware.fail_read = false;
  const std::uint64_t updates = rig.localization.updates.load();
  rig.cycle(10.0);
  EXPECT_EQ(rig.localization.hand_overs.load(), 1U);
  EXPECT_EQ(rig.localization.updates.load(), updates);  // the gap's motion went into the hand-over
}

TEST(SwapStage, ATakenSwapRetiresTheOutgoingInstanceAndARefusalTheIncoming) {
  RtLog log;
  LoopEvents events(log);
  PluginGuard guard;
  FakeLocalization first;
  FakeLocalization second;
  FakeDrivetrain drivetrain;
  Drivetrain* active_drivetrain = &drivetrain;
  SwapStage stage(first, "first");
  EXPECT_EQ(stage.active(), &first);
  ASSERT_TRUE(stage.request_localization(&second, "second"));
  EXPECT_FALSE(stage.request_localization(&second, "second"));  // one in flight
  EXPECT_TRUE(stage.pending());
  ModelSettings model;
  EXPECT_FALSE(stage.take(1.0, false, 2, active_drivetrain, model, guard, events));
  EXPECT_EQ(stage.active(), &second);
  EXPECT_FALSE(stage.pending());
  LoopSwap* retired = stage.take_retired();
  ASSERT_NE(retired, nullptr);
  EXPECT_TRUE(retired->outcome.taken);
  EXPECT_EQ(retired->localization, &first);
  StateSnapshot state;
  stage.publish(state);
  EXPECT_STREQ(state.localization_plugin.data(), "second");
  EXPECT_EQ(state.localization_swaps, 1U);

  first.refuse_hand_over = true;
  ASSERT_TRUE(stage.request_localization(&first, "first"));
  (void)stage.take(1.1, false, 2, active_drivetrain, model, guard, events);
  EXPECT_EQ(stage.active(), &second);
  retired = stage.take_retired();
  ASSERT_NE(retired, nullptr);
  EXPECT_FALSE(retired->outcome.taken);
  EXPECT_STREQ(retired->outcome.refusal.data(), "fake hand-over refusal");
  EXPECT_EQ(events.fault_count(), 0U);  // no fault: the robot lost nothing
}

TEST(SwapStage, ANewDrivetrainWaitsForRestAndMayBeWithdrawn) {
  RtLog log;
  LoopEvents events(log);
  PluginGuard guard;
  FakeLocalization first;
  FakeLocalization second;
  FakeDrivetrain old_drivetrain;
  FakeDrivetrain new_drivetrain;
  Drivetrain* active_drivetrain = &old_drivetrain;
  SwapStage stage(first, "first");
  LoopSwap swap;
  swap.localization = &second;
  swap.drivetrain = &new_drivetrain;
  swap.model.wheel_encoder_resolution_rad = 0.001;
  ASSERT_TRUE(stage.request(&swap));
  ModelSettings model;
  EXPECT_FALSE(stage.take(1.0, false, 2, active_drivetrain, model, guard, events));
  EXPECT_TRUE(stage.pending());  // waits
  EXPECT_TRUE(stage.withdraw(&swap));
  EXPECT_FALSE(stage.pending());
  ASSERT_TRUE(stage.request(&swap));
  EXPECT_TRUE(stage.take(1.1, true, 2, active_drivetrain, model, guard, events));
  EXPECT_EQ(active_drivetrain, &new_drivetrain);
  EXPECT_EQ(model.wheel_encoder_resolution_rad, 0.001);
  EXPECT_EQ(stage.take_retired(), &swap);
  EXPECT_EQ(swap.drivetrain, &old_drivetrain);
  StateSnapshot state;
  stage.publish(state);
  EXPECT_EQ(state.model_swaps, 1U);
}

TEST(SwapStage, AtRestNeedsZeroSetpointsAndMeasuredStillJoints) {
  StateSnapshot last;
  last.has_joint_rates = true;
  EXPECT_TRUE(at_rest(last, true, 2));
  EXPECT_FALSE(at_rest(last, false, 2));
  last.wheel_rate_radps[1] = kAtRestJointRateRadps;
  EXPECT_FALSE(at_rest(last, true, 2));
  EXPECT_TRUE(at_rest(last, true, 1));
  last.has_joint_rates = false;
  EXPECT_FALSE(at_rest(last, true, 1));
}

}  // namespace
}  // namespace swivel::rt
