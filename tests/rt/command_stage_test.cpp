// SPDX-License-Identifier: Apache-2.0
// CommandStage: the newest command wins, a non-finite one is rejected, a timed-out one ends
// the motion (a fault only when it asked for motion); the limits shape the twist, the stop's
// deceleration brings it to zero once the controlled stop is taken, and no command moves the
// robot after it.

#include "swivel/rt/command_stage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace swivel::rt {
namespace {

constexpr double kPeriodS = 0.001;

CommandLimits limits() {
  CommandLimits l;
  l.limits.linear_acceleration_mps2 = 1.0;  // 1 mm/s per cycle
  l.stop_linear_deceleration_mps2 = 2.0;
  l.stop_angular_deceleration_radps2 = std::numeric_limits<double>::infinity();
  l.command_timeout_s = 0.1;
  l.period_s = kPeriodS;
  return l;
}

VelocityCommand command(double vx_mps, double received_s, std::uint64_t sequence = 1) {
  VelocityCommand c;
  c.twist = {vx_mps, 0.0, 0.0};
  c.received_s = received_s;
  c.sequence = sequence;
  return c;
}

// The stages side by side as the loop holds them; the padding does not matter in a test.
// NOLINTNEXTLINE(clang-analyzer-optin.performance.Padding)
struct Rig {
  RtLog log;
  LoopEvents events{log};
  CommandStage stage;
  double t_s = 1.0;

  explicit Rig(const CommandLimits& l = limits()) : stage(l) {}

  // One cycle: takes the command and steps the limits; returns the limited twist.
  Twist2 cycle() {
    const CycleTime time{t_s + kPeriodS, true, t_s};
    t_s += kPeriodS;
    stage.take_stop_request(time, events);
    stage.take_command(t_s, events);
    const bool moving = stage.moving(false);
    return stage.limit(moving ? stage.command_twist() : Twist2{}, !moving, time);
  }
};

TEST(CommandStage, TheNewestCommandWinsAndTheLimitsShapeIt) {
  Rig rig;
  rig.stage.push(command(9.0, rig.t_s, 1));
  rig.stage.push(command(0.5, rig.t_s, 2));  // replaces the one not taken yet
  Twist2 twist;
  for (int k = 0; k < 10; ++k) twist = rig.cycle();
  EXPECT_TRUE(rig.stage.moving(false));
  EXPECT_FALSE(rig.stage.moving(true));  // held by a fault, a calibration, the final cycle
  EXPECT_EQ(rig.stage.command_twist().vx_mps, 0.5);
  EXPECT_NEAR(twist.vx_mps, 0.010, 1e-9);  // 1 m/s^2 for 10 ms
}

TEST(CommandStage, ANonFiniteCommandIsRejectedAndATimeoutEndsTheMotion) {
  Rig rig;
  rig.stage.push(command(std::nan(""), rig.t_s));
  rig.cycle();
  EXPECT_EQ(rig.events.transient(), FaultCode::kNonFiniteCommand);
  EXPECT_FALSE(rig.stage.moving(false));
  rig.stage.push(command(0.2, rig.t_s));
  rig.cycle();
  EXPECT_EQ(rig.events.transient(), FaultCode::kNone);  // a fresh command resumes
  EXPECT_TRUE(rig.stage.moving(false));
  for (int k = 0; k < 101; ++k) rig.cycle();
  EXPECT_FALSE(rig.stage.moving(false));
  EXPECT_EQ(rig.events.transient(), FaultCode::kCommandTimeout);

  rig.stage.push(command(0.0, rig.t_s));  // a stream that ended with a stop: no fault
  rig.cycle();
  EXPECT_EQ(rig.events.transient(), FaultCode::kNone);
  for (int k = 0; k < 101; ++k) rig.cycle();
  EXPECT_FALSE(rig.stage.moving(false));
  EXPECT_EQ(rig.events.transient(), FaultCode::kNone);
}

TEST(CommandStage, TheControlledStopDeceleratesAndIgnoresLaterCommands) {
  CommandLimits no_model_acceleration = limits();
  no_model_acceleration.limits.linear_acceleration_mps2.reset();  // the stop's 2 m/s^2 applies
  Rig rig(no_model_acceleration);
  rig.stage.push(command(0.05, rig.t_s));
  Twist2 twist = rig.cycle();
  ASSERT_NEAR(twist.vx_mps, 0.05, 1e-9);
  rig.stage.request_stop(rig.t_s + kPeriodS);
  rig.stage.request_stop(0.0);  // later calls change nothing
  twist = rig.cycle();
  EXPECT_TRUE(rig.stage.stopping());
  EXPECT_LT(twist.vx_mps, 0.05);
  rig.stage.push(command(0.05, rig.t_s));
  for (int k = 0; k < 30; ++k) twist = rig.cycle();
  EXPECT_FALSE(rig.stage.moving(false));
  EXPECT_EQ(twist.vx_mps, 0.0);  // 2 m/s^2 from 0.05 m/s: 25 ms
}

TEST(CommandStage, FollowsADrivetrainThatScaledTheTwistDown) {
  CommandLimits fast = limits();
  fast.limits.linear_acceleration_mps2 = 100.0;  // 0.1 m/s per cycle
  CommandStage stage(fast);
  CycleTime time{1.0, false, 0.0};
  Twist2 twist;
  for (int k = 0; k < 10; ++k) {
    twist = stage.limit({1.0, 0.0, 0.0}, false, time);
    time = CycleTime{time.now_s + kPeriodS, true, time.now_s};
  }
  ASSERT_NEAR(twist.vx_mps, 1.0, 1e-9);
  stage.follow(twist, {0.4, 0.0, 0.0});  // the drivetrain's own limits gave 0.4 m/s
  // The stop ramps down from the speed the robot got, not from the one it was asked for.
  twist = stage.limit({}, true, time);
  EXPECT_NEAR(twist.vx_mps, 0.3, 1e-9);
  stage.reset({0.05, 0.0, 0.0});
  time = CycleTime{time.now_s + kPeriodS, true, time.now_s};
  twist = stage.limit({}, true, time);
  EXPECT_NEAR(twist.vx_mps, 0.0, 1e-9);
}

}  // namespace
}  // namespace swivel::rt
