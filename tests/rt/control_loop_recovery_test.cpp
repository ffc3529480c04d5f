// SPDX-License-Identifier: Apache-2.0
// The loop's motion limits, its controlled stop, and the ways out of a fault: one-shot clear
// requests, setting the pose, the hardware's error hook and pause, and a hot swap that rolls
// back. In-process fakes on synthetic time (run_cycle), except where a loop thread is the
// point.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "alloc_guard.hpp"
#include "fake_plugins.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::rt {
namespace {

using test::FakeDrivetrain;
using test::FakeHardware;
using test::FakeLocalization;

constexpr double kDtS = 0.001;

LoopOptions options_with(const MotionLimits& limits = {}) {
  LoopOptions o;
  o.rate_hz = 1.0 / kDtS;
  o.realtime = false;
  o.limits = limits;
  return o;
}

class Rig {
 public:
  explicit Rig(const LoopOptions& options = options_with())
      : loop(std::make_unique<ControlLoop>(options, hardware, drivetrain, localization, "a")) {}

  void command(double vx_mps, double wz_radps = 0.0) {
    VelocityCommand c;
    c.twist = {vx_mps, 0.0, wz_radps};
    c.received_s = t_s;
    c.sequence = ++sequence;
    (void)loop->push_command(c);
  }
  void step(int cycles = 1) {
    for (int i = 0; i < cycles; ++i) {
      t_s += kDtS;
      loop->run_cycle(t_s);
    }
  }
  void drive(double vx_mps, int cycles) {
    for (int i = 0; i < cycles; ++i) {
      if (i % 10 == 0) command(vx_mps);
      step();
    }
  }
  // The loop's answer to the request just made, after one cycle.
  LoopReply answer() {
    step();
    LoopReply reply;
    EXPECT_TRUE(loop->take_reply(reply)) << "no reply";
    return reply;
  }
  [[nodiscard]] StateSnapshot state() const { return loop->latest(); }
  [[nodiscard]] double vx() const { return loop->latest().command_twist.vx_mps; }

  FakeHardware hardware;
  FakeDrivetrain drivetrain;
  FakeLocalization localization;
  std::unique_ptr<ControlLoop> loop;
  double t_s = 100.0;
  std::uint64_t sequence = 0;
};

MotionLimits acceleration_limit(double mps2) {
  MotionLimits limits;
  limits.linear_acceleration_mps2 = mps2;
  limits.angular_acceleration_radps2 = 2.0 * mps2;
  return limits;
}

TEST(LoopLimits, CommandsAccelerateAtTheModelsLimit) {
  Rig rig(options_with(acceleration_limit(0.5)));
  rig.drive(0.3, 100);
  EXPECT_NEAR(rig.vx(), 0.05, 1e-9);  // 0.1 s at 0.5 m/s^2
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  rig.drive(0.3, 600);
  EXPECT_NEAR(rig.vx(), 0.3, 1e-12);
  // The wheels were given the limited twist.
  EXPECT_NEAR(rig.hardware.last_left_radps.load(), 0.3 / test::kFakeWheelRadiusM, 1e-9);
}

TEST(LoopLimits, AFaultStopRampsDownAtTheModelsDeceleration) {
  Rig rig(options_with(acceleration_limit(1.0)));
  rig.drive(0.5, 1000);
  ASSERT_NEAR(rig.vx(), 0.5, 1e-12);
  Pose2 at_fault;
  ASSERT_TRUE(rig.hardware.ground_truth(at_fault));

  rig.localization.fail_update = true;
  rig.drive(0.5, 1);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_NEAR(rig.vx(), 0.5 - 1.0 * kDtS, 1e-9);  // one cycle's deceleration, not zero
  double previous = rig.vx();
  for (int k = 0; k < 600; ++k) {
    rig.drive(0.5, 1);  // commands keep coming; the safe stop ignores them
    ASSERT_LE(rig.vx(), previous);
    ASSERT_GE(previous - rig.vx(), 0.0);
    ASSERT_LE(previous - rig.vx(), 1.0 * kDtS + 1e-12) << k;
    previous = rig.vx();
  }
  EXPECT_EQ(rig.vx(), 0.0);
  Pose2 at_rest;
  ASSERT_TRUE(rig.hardware.ground_truth(at_rest));
  // v^2 / (2 a) plus one cycle at v.
  EXPECT_LE(at_rest.x_m - at_fault.x_m, 0.5 * 0.5 / 2.0 + 0.5 * kDtS);
  EXPECT_GT(at_rest.x_m - at_fault.x_m, 0.5 * 0.5 / 2.0 - 0.5 * kDtS);
}

TEST(LoopLimits, WithoutModelLimitsTheStopUsesItsOwnDeceleration) {
  LoopOptions options = options_with();
  options.stop_linear_deceleration_mps2 = 2.0;
  Rig rig(options);
  rig.drive(0.4, 20);
  EXPECT_EQ(rig.vx(), 0.4);  // commands are not limited: the model has no limits
  for (int k = 0; k < 1000 && rig.state().fault != FaultCode::kCommandTimeout; ++k) rig.step();
  ASSERT_EQ(rig.state().fault, FaultCode::kCommandTimeout);
  EXPECT_NEAR(rig.vx(), 0.4 - 2.0 * kDtS, 1e-9);  // the stop's first cycle
  rig.step(198);
  EXPECT_NEAR(rig.vx(), 0.4 - 2.0 * 199 * kDtS, 1e-9);
  rig.step(1);
  EXPECT_EQ(rig.vx(), 0.0);
}

TEST(LoopLimits, ThePlainStopIsImmediateWithoutAnyDeceleration) {
  Rig rig;
  rig.drive(0.4, 20);
  rig.localization.fail_update = true;
  rig.step();
  EXPECT_EQ(rig.vx(), 0.0);
  EXPECT_EQ(rig.hardware.last_left_radps.load(), 0.0);
}

TEST(LoopLimits, TheLimiterFollowsTheDrivetrainsOwnLimits) {
  Rig rig(options_with(acceleration_limit(1.0)));
  rig.drivetrain.max_speed_mps = 0.5;
  rig.drive(2.0, 3000);  // the limiter alone would be at 2 m/s by now
  EXPECT_NEAR(rig.vx(), 0.5, 1e-12);
  rig.drive(0.0, 1);
  // Decelerating from the 0.5 m/s the robot has, not from 2 m/s.
  EXPECT_NEAR(rig.vx(), 0.5 - 1.0 * kDtS, 1e-9);
  rig.drive(0.0, 500);
  EXPECT_EQ(rig.vx(), 0.0);
}

TEST(ControlledStop, IgnoresCommandsAndBringsTheRobotToRest) {
  Rig rig(options_with(acceleration_limit(1.0)));
  rig.drive(0.5, 1000);
  Pose2 asked;
  ASSERT_TRUE(rig.hardware.ground_truth(asked));
  rig.loop->request_controlled_stop(rig.t_s);
  rig.drive(0.5, 1);
  EXPECT_TRUE(rig.state().stopping);
  // Braking counts from the request, a period ago, and the new setpoint is the ramp's value
  // half a period ahead, when it is in force.
  EXPECT_NEAR(rig.vx(), 0.5 - 1.5 * kDtS, 1e-9);
  rig.drive(0.5, 499);
  EXPECT_NEAR(rig.vx(), 0.0, 1e-12);
  Pose2 at_rest;
  ASSERT_TRUE(rig.hardware.ground_truth(at_rest));
  // What the robot travelled after the request: v^2 / (2 a), to within a fraction of a cycle.
  EXPECT_NEAR(at_rest.x_m - asked.x_m, 0.5 * 0.5 / 2.0, 0.25 * 0.5 * kDtS);
  rig.drive(0.5, 100);  // still commanded: stays at rest
  EXPECT_EQ(rig.vx(), 0.0);
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  EXPECT_EQ(rig.hardware.last_left_radps.load(), 0.0);
}

TEST(ClearRequest, IsRefusedWhileTheCausePersistsAndDoesNotWait) {
  Rig rig;
  rig.drive(0.3, 50);
  rig.hardware.fail_read = true;
  rig.step();
  ASSERT_EQ(rig.state().mode, LoopMode::kSafeStop);

  rig.loop->request_clear(41);
  LoopReply refused = rig.answer();
  EXPECT_EQ(refused.id, 41U);
  EXPECT_FALSE(refused.ok);
  EXPECT_EQ(refused.fault, FaultCode::kHardwareError);
  EXPECT_STREQ(refused.detail.data(), "hardware_error");  // the fake gives no text

  rig.hardware.fail_read = false;  // the cause goes; a refused request does not linger
  rig.step(100);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);

  rig.loop->request_clear(42);
  const LoopReply cleared = rig.answer();
  EXPECT_EQ(cleared.id, 42U);
  EXPECT_TRUE(cleared.ok);
  EXPECT_EQ(cleared.fault, FaultCode::kHardwareError);
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle);
  rig.drive(0.3, 20);  // only a fresh command moves it
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
}

TEST(ClearRequest, ACommandTimeoutIsRefusedUntilCommandsReturn) {
  Rig rig;
  rig.drive(0.3, 20);
  rig.step(600);
  ASSERT_EQ(rig.state().fault, FaultCode::kCommandTimeout);
  rig.loop->request_clear(1);
  const LoopReply reply = rig.answer();
  EXPECT_FALSE(reply.ok);
  EXPECT_EQ(reply.fault, FaultCode::kCommandTimeout);
  EXPECT_STREQ(reply.detail.data(), "velocity command timed out");
}

TEST(ClearRequest, NothingToClearIsAnswered) {
  Rig rig;
  rig.step(5);
  rig.loop->request_clear(9);
  const LoopReply reply = rig.answer();
  EXPECT_TRUE(reply.ok);
  EXPECT_EQ(reply.fault, FaultCode::kNone);
}

TEST(SetPoseRequest, GoesThroughTheActiveLocalizationsHandOver) {
  Rig rig;
  rig.step(5);
  const std::uint64_t hand_overs = rig.localization.hand_overs.load();
  PoseEstimate pose;
  pose.pose = {1.5, -2.0, 0.75};
  pose.has_covariance = true;
  pose.covariance = {0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.04};
  rig.loop->request_set_pose(pose, 3);
  const LoopReply reply = rig.answer();
  EXPECT_TRUE(reply.ok);
  EXPECT_EQ(reply.id, 3U);
  EXPECT_EQ(rig.localization.hand_overs.load(), hand_overs + 1);
  const PoseEstimate now = rig.state().estimate;
  EXPECT_EQ(now.pose.x_m, 1.5);  // standing still: no odometry on top
  EXPECT_EQ(now.pose.y_m, -2.0);
  EXPECT_EQ(now.pose.yaw_rad, 0.75);
  EXPECT_EQ(now.covariance[8], 0.04);
}

TEST(SetPoseRequest, ARefusalLeavesTheEstimateAndRaisesNoFault) {
  Rig rig;
  rig.drive(0.2, 100);
  rig.localization.refuse_hand_over = true;
  const Pose2 before = rig.state().estimate.pose;
  PoseEstimate pose;
  pose.pose = {5.0, 5.0, 0.0};
  rig.loop->request_set_pose(pose, 4);
  rig.command(0.2);
  const LoopReply reply = rig.answer();
  EXPECT_FALSE(reply.ok);
  EXPECT_STREQ(reply.detail.data(), "fake hand-over refusal");
  EXPECT_LT(std::abs(rig.state().estimate.pose.x_m - before.x_m), 0.01);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
}

TEST(HardwareError, OnErrorIsCalledOnceUntilAClear) {
  Rig rig;
  rig.drive(0.3, 20);
  rig.hardware.fail_read = true;
  rig.step();
  EXPECT_EQ(rig.hardware.on_errors.load(), 1U);
  EXPECT_TRUE(rig.state().hardware_in_error);
  rig.step(50);
  EXPECT_EQ(rig.hardware.on_errors.load(), 1U);
  rig.hardware.fail_read = false;
  rig.loop->request_clear(1);
  EXPECT_TRUE(rig.answer().ok);
  EXPECT_FALSE(rig.state().hardware_in_error);
  rig.hardware.fail_read = true;
  rig.step();
  EXPECT_EQ(rig.hardware.on_errors.load(), 2U);
}

TEST(HardwarePause, IsGrantedOnlyToAStoppedRobotAndStopsTheHardwareCalls) {
  FakeHardware hardware;
  FakeDrivetrain drivetrain;
  FakeLocalization localization;
  ControlLoop loop(options_with(), hardware, drivetrain, localization, "a");
  (void)loop.start();
  EXPECT_FALSE(loop.pause_hardware(1.0)) << "granted without a fault";

  hardware.fail_read = true;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (loop.latest().mode != LoopMode::kSafeStop && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_EQ(loop.latest().mode, LoopMode::kSafeStop);
  ASSERT_TRUE(loop.pause_hardware(5.0));
  const std::uint64_t reads = hardware.reads.load();
  const std::uint64_t cycles = loop.latest().cycle;
  while (loop.latest().cycle < cycles + 20 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_GE(loop.latest().cycle, cycles + 20) << "the loop stopped cycling";
  EXPECT_EQ(hardware.reads.load(), reads) << "the hardware was called while paused";
  loop.resume_hardware();
  while (hardware.reads.load() == reads && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_GT(hardware.reads.load(), reads);
  loop.stop();
}

TEST(SwapRollback, ARefusedHandOverKeepsTheOutgoingInstance) {
  Rig rig;
  rig.drive(0.3, 200);
  FakeLocalization refusing;
  refusing.refuse_hand_over = true;
  const StateSnapshot before = rig.state();
  ASSERT_TRUE(rig.loop->request_localization_swap(&refusing, "refusing"));
  rig.drive(0.3, 1);

  SwapOutcome outcome;
  EXPECT_EQ(rig.loop->take_retired_localization(&outcome), &refusing);
  EXPECT_FALSE(outcome.taken);
  EXPECT_STREQ(outcome.refusal.data(), "fake hand-over refusal");
  EXPECT_EQ(rig.loop->active_localization(), &rig.localization);
  const StateSnapshot after = rig.state();
  EXPECT_STREQ(after.localization_plugin.data(), "a");
  EXPECT_EQ(after.localization_swaps, before.localization_swaps);
  EXPECT_EQ(after.fault, FaultCode::kNone);
  EXPECT_EQ(after.mode, LoopMode::kVelocity);
  EXPECT_EQ(refusing.updates.load(), 0U);

  // The next swap goes through.
  FakeLocalization working;
  ASSERT_TRUE(rig.loop->request_localization_swap(&working, "working"));
  rig.drive(0.3, 1);
  EXPECT_EQ(rig.loop->take_retired_localization(&outcome), &rig.localization);
  EXPECT_TRUE(outcome.taken);
  EXPECT_EQ(rig.loop->active_localization(), &working);
}

TEST(LoopRecoveryAllocations, LimitsStopsClearsPosesAndRollbacksAllocateNothing) {
  MotionLimits limits = acceleration_limit(1.0);
  limits.linear_jerk_mps3 = 20.0;
  limits.linear_velocity_mps = 0.8;
  Rig rig(options_with(limits));
  FakeLocalization refusing;
  refusing.refuse_hand_over = true;
  test::HeapCounts counts;
  std::thread loop_thread([&] {
    rig.drive(0.5, 200);  // warm-up
    test::AllocCounter counter;
    rig.drive(1.0, 1500);
    rig.hardware.fail_read = true;
    rig.drive(1.0, 10);
    rig.loop->request_clear(1);
    rig.drive(1.0, 500);
    LoopReply reply;
    (void)rig.loop->take_reply(reply);
    rig.hardware.fail_read = false;
    rig.loop->request_clear(2);
    rig.drive(0.5, 500);
    (void)rig.loop->take_reply(reply);
    PoseEstimate pose;
    pose.pose = {1.0, 2.0, 3.0};
    rig.loop->request_set_pose(pose, 3);
    rig.drive(0.5, 10);
    (void)rig.loop->take_reply(reply);
    (void)rig.loop->request_localization_swap(&refusing, "refusing");
    rig.drive(0.5, 10);
    (void)rig.loop->take_retired_localization();
    rig.loop->request_controlled_stop(rig.t_s);
    rig.drive(0.5, 1000);
    counts = counter.counts();
  });
  loop_thread.join();
  EXPECT_EQ(counts.allocations, 0U)
      << "first allocation: " << counts.first_allocation_bytes << " bytes";
  EXPECT_EQ(counts.deallocations, 0U);
  EXPECT_TRUE(rig.state().stopping);
  EXPECT_EQ(rig.vx(), 0.0);
  EXPECT_EQ(rig.hardware.on_errors.load(), 1U);
  EXPECT_EQ(rig.state().estimate.pose.yaw_rad, 3.0);
}

}  // namespace
}  // namespace swivel::rt
