// SPDX-License-Identifier: Apache-2.0
// Rows of docs/faults.md for the velocity command stream: it stops, floods, or carries
// non-finite or absurd values.

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <thread>

#include "fault_rig.hpp"

namespace swivel::faults {
namespace {

constexpr double kVxMps = 0.3;

TEST(CommandFaults, StreamThatStopsTimesOutToZero) {
  FaultRig rig;  // command timeout 0.5 s
  rig.drive(kVxMps, 0.0, 0.0, 300);
  ASSERT_TRUE(rig.command(kVxMps, 0.0, 0.0));
  const double last_command_s = rig.t_s;
  // Still moving while the newest command is no older than the timeout.
  while (rig.t_s + FaultRig::kDtS - last_command_s <= 0.5 - 1e-9) {
    rig.step();
    ASSERT_EQ(rig.state().mode, LoopMode::kVelocity) << "at age " << rig.t_s - last_command_s;
  }
  const StateSnapshot moving = rig.state();
  // The first cycle past the timeout stops the robot.
  rig.step(2);
  const StateSnapshot stopped = rig.state();
  EXPECT_EQ(stopped.mode, LoopMode::kIdle);
  EXPECT_EQ(stopped.fault, FaultCode::kCommandTimeout);
  EXPECT_EQ(stopped.fault_count, moving.fault_count + 1);
  EXPECT_EQ(max_wheel_setpoint(stopped), 0.0);
  EXPECT_EQ(stopped.command_twist.vx_mps, 0.0);
  rig.step(300);
  EXPECT_EQ(rig.state().fault, FaultCode::kCommandTimeout);
  EXPECT_EQ(rig.state().fault_count, stopped.fault_count) << "one event per timeout";
  EXPECT_EQ(rig.state().cycle, stopped.cycle + 300);
  EXPECT_NE(rig.log().find("fault command_timeout (#1): velocity command timed out"),
            std::string::npos);
  // A fresh command resumes on its own: a timeout is not latched.
  rig.drive(kVxMps, 0.0, 0.0, 1);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  EXPECT_NEAR(rig.state().command_twist.vx_mps, kVxMps, 1e-12);
}

// Nav2 sends a zero twist at the end of every goal and then nothing: the robot is idle, which
// is no fault (diagnostics stay OK), however long the silence lasts.
TEST(CommandFaults, StreamThatEndsWithAStopIdlesWithoutAFault) {
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 300);
  rig.drive(0.0, 0.0, 0.0, 50);  // the source's last commands: a stop
  const StateSnapshot stopped = rig.state();
  rig.step(3000);  // six timeouts of silence
  const StateSnapshot idle = rig.state();
  EXPECT_EQ(idle.mode, LoopMode::kIdle);
  EXPECT_EQ(idle.fault, FaultCode::kNone) << fault_code_name(idle.fault);
  EXPECT_EQ(idle.fault_detail[0], '\0');
  EXPECT_EQ(idle.fault_count, stopped.fault_count);
  EXPECT_EQ(max_wheel_setpoint(idle), 0.0);
  EXPECT_EQ(rig.log().find("command_timeout"), std::string::npos) << rig.log();

  // The same stream going silent inside a motion is a timeout again.
  rig.drive(kVxMps, 0.0, 0.0, 100);
  rig.step(600);
  EXPECT_EQ(rig.state().fault, FaultCode::kCommandTimeout);
  EXPECT_EQ(rig.state().fault_count, stopped.fault_count + 1);
  EXPECT_EQ(max_wheel_setpoint(rig.state()), 0.0);
}

TEST(CommandFaults, NonFiniteCommandIsRejectedAndStops) {
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(rig.command(nan, 0.0, 0.0));
  rig.step();
  StateSnapshot s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kIdle);
  EXPECT_EQ(s.fault, FaultCode::kNonFiniteCommand);
  EXPECT_EQ(s.fault_count, 1U);
  EXPECT_EQ(max_wheel_setpoint(s), 0.0);
  // The valid command seen before is discarded too: nothing moves until a fresh one.
  rig.step(50);
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle);
  ASSERT_TRUE(rig.command(0.0, 0.0, std::numeric_limits<double>::infinity()));
  rig.step();
  EXPECT_EQ(rig.state().fault_count, 2U) << "every rejected command is an event";
  EXPECT_NE(rig.log().find("non-finite velocity command"), std::string::npos);
  rig.drive(kVxMps, 0.0, 0.0, 1);
  s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kVelocity);
  EXPECT_EQ(s.fault, FaultCode::kNone);
  EXPECT_GT(max_wheel_setpoint(s), 1.0);
}

TEST(CommandFaults, HugeCommandIsDesaturatedToTheWheelLimitsOnDifferential) {
  FaultRig rig;  // differential: max_wheel_rate_radps 20 (default)
  rig.drive(1e9, 0.0, 1e9, 20);
  const StateSnapshot s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kVelocity);
  EXPECT_EQ(s.fault, FaultCode::kNone);
  // One factor on the whole twist: the faster wheel exactly at the limit, curvature kept.
  EXPECT_NEAR(max_wheel_setpoint(s), 20.0, 1e-9);
  EXPECT_LE(max_wheel_setpoint(s), 20.0 + 1e-12);
  EXPECT_NEAR(s.command_twist.wz_radps / s.command_twist.vx_mps, 1.0, 1e-12);
  // Wheel speeds vx -+ wz * track / 2 with vx = wz and track 0.4 m: w_l / w_r = 0.8 / 1.2.
  EXPECT_NEAR(s.modules[0].wheel_rate_cmd_radps / s.modules[1].wheel_rate_cmd_radps,
              (1.0 - 0.2) / (1.0 + 0.2), 1e-9);
}

TEST(CommandFaults, HugeCommandIsDesaturatedToTheActuatorLimitsOnSwpc) {
  RigOptions options;
  options.robot = "swpc4";
  options.drivetrain = "swpc";
  FaultRig rig(options);          // max_wheel_rate_radps 40, max_steer_rate_radps 12 (defaults)
  rig.drive(0.2, 0.0, 0.0, 200);  // casters aligned, moving
  for (int i = 0; i < 200; ++i) {
    rig.drive(1e9, -1e9, 1e9, 1);
    const StateSnapshot s = rig.state();
    ASSERT_EQ(s.mode, LoopMode::kVelocity);
    for (std::uint32_t m = 0; m < s.module_count; ++m) {
      ASSERT_LE(std::abs(s.modules[m].wheel_rate_cmd_radps), 40.0 + 1e-9) << "module " << m;
      ASSERT_LE(std::abs(s.modules[m].steer_rate_cmd_radps), 12.0 + 1e-9) << "module " << m;
    }
    // The most loaded actuator sits exactly at its limit.
    ASSERT_TRUE(std::abs(max_wheel_setpoint(s) - 40.0) < 1e-9 ||
                std::abs(max_steer_setpoint(s) - 12.0) < 1e-9);
  }
  EXPECT_EQ(rig.state().fault_count, 0U);
}

TEST(CommandFaults, FloodKeepsTheNewestCommand) {
  // A producer thread sends 100 commands per cycle (100x the loop rate) in lockstep with
  // the cycles, so the outcome is deterministic. Command k of cycle c carries vx = k mm/s;
  // the last of every burst is a stop on every 50th cycle. The latest-value slot keeps only
  // the newest: every cycle applies the burst's last command, the stops included.
  FaultRig rig;
  constexpr int kCycles = 300;
  constexpr int kPerCycle = 100;
  auto last_vx = [](int c) { return c % 50 == 0 ? 0.0 : 0.001 * kPerCycle; };
  std::atomic<int> requested{0};
  std::atomic<int> done{0};
  std::atomic<int> refused{0};
  std::thread producer([&] {
    for (int c = 1; c <= kCycles; ++c) {
      while (requested.load(std::memory_order_acquire) < c) std::this_thread::yield();
      for (int k = 1; k <= kPerCycle; ++k) {
        VelocityCommand cmd;
        cmd.twist.vx_mps = k == kPerCycle ? last_vx(c) : 0.001 * k;
        cmd.received_s = rig.t_s + FaultRig::kDtS;  // the cycle about to run
        cmd.sequence = (static_cast<std::uint64_t>(c) * kPerCycle) + static_cast<std::uint64_t>(k);
        if (!rig.loop->push_command(cmd)) refused.fetch_add(1, std::memory_order_relaxed);
      }
      done.store(c, std::memory_order_release);
    }
  });
  for (int c = 1; c <= kCycles; ++c) {
    requested.store(c, std::memory_order_release);
    while (done.load(std::memory_order_acquire) < c) std::this_thread::yield();
    rig.step();
    const StateSnapshot s = rig.state();
    ASSERT_EQ(s.mode, LoopMode::kVelocity) << "cycle " << c;
    ASSERT_EQ(s.command_twist.vx_mps, last_vx(c)) << "cycle " << c;
  }
  producer.join();
  EXPECT_EQ(refused.load(), 0);
  EXPECT_EQ(rig.state().cycle, static_cast<std::uint64_t>(kCycles));
  EXPECT_EQ(rig.state().fault_count, 0U);
}

TEST(CommandFaults, StopSentAfterAFloodIsAppliedInTheNextCycle) {
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 100);
  for (int k = 0; k < 1000; ++k) rig.command(kVxMps, 0.0, 0.0);
  rig.command(0.0, 0.0, 0.0);
  rig.step();
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.state().command_twist.vx_mps, 0.0);
  EXPECT_EQ(max_wheel_setpoint(rig.state()), 0.0);
}

TEST(CommandFaults, FreeRunningFloodNeverStallsTheLoop) {
  // The same flood without lockstep: whatever interleaving happens, every cycle runs, the
  // loop applies one of the commands sent, and nothing is raised.
  FaultRig rig;
  rig.drive(0.05, 0.0, 0.0, 10);
  std::atomic<bool> stop{false};
  const double sent_s = rig.t_s;  // every command stays fresh for the 400 cycles below
  std::thread producer([&] {
    std::uint64_t k = 0;
    while (!stop.load(std::memory_order_acquire)) {
      VelocityCommand cmd;
      cmd.twist.vx_mps = 0.001 * static_cast<double>(1 + k % 100);
      cmd.received_s = sent_s;
      cmd.sequence = ++k;
      (void)rig.loop->push_command(cmd);
    }
  });
  for (int c = 0; c < 400; ++c) {
    rig.step();
    const StateSnapshot s = rig.state();
    ASSERT_GE(s.command_twist.vx_mps, 0.001 - 1e-12);
    ASSERT_LE(s.command_twist.vx_mps, 0.100 + 1e-12);
  }
  stop.store(true, std::memory_order_release);
  producer.join();
  EXPECT_EQ(rig.state().cycle, 410U);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.state().fault_count, 0U);
}

}  // namespace
}  // namespace swivel::faults
