// SPDX-License-Identifier: Apache-2.0
// The whole fault sequence of docs/faults.md on the real plugins, with the allocation guard
// armed on the cycling thread only: no heap operation while faults are raised, reacted to
// and cleared. Preparing plugin instances (the loader) and the flooding producer run on
// other threads, as they do in the daemon. The throwing-plugin row is left out: throwing
// allocates the exception object (__cxa_allocate_exception calls malloc), which the last
// test shows.

#include <gtest/gtest.h>

#include <atomic>
#include <limits>
#include <thread>

#include "alloc_guard.hpp"
#include "fault_rig.hpp"

namespace swivel::faults {
namespace {

using test::AllocCounter;
using test::HeapCounts;

void drive_with_fixes(FaultRig& rig, int cycles, bool fixes) {
  for (int i = 0; i < cycles; ++i) {
    if (i % 10 == 0) {
      rig.command(0.3, 0.0, 0.2);
      if (fixes) {
        MotionCaptureSample fix;
        fix.valid = true;
        fix.stamp_s = rig.t_s;
        fix.pose = rig.state().truth;
        (void)rig.loop->push_motion_capture(fix);
      }
    }
    rig.step();
  }
}

TEST(FaultAllocations, WholeFaultSequenceAllocatesNothingOnTheLoopThread) {
  RigOptions options;
  options.localization = "kalman";
  FaultRig rig(options);
  auto failing = rig.make_localization("update_error", "{fail_after_cycles: 50}");
  auto working = rig.make_localization("raw_eg", "{}");
  Localization* kalman = rig.localization.get();

  // Flood producer: 100 commands per cycle on request, in lockstep.
  std::atomic<int> requested{0};
  std::atomic<int> done{0};
  std::atomic<bool> quit{false};
  std::thread producer([&] {
    for (int c = 1;; ++c) {
      while (requested.load(std::memory_order_acquire) < c) {
        if (quit.load(std::memory_order_acquire)) return;
        std::this_thread::yield();
      }
      for (int k = 1; k <= 100; ++k) {
        VelocityCommand cmd;
        cmd.twist.vx_mps = 0.002 * k;
        cmd.received_s = rig.t_s + FaultRig::kDtS;
        (void)rig.loop->push_command(cmd);
      }
      done.store(c, std::memory_order_release);
    }
  });

  HeapCounts counts;
  StateSnapshot after_sensor_faults;
  Localization* retired[2] = {nullptr, nullptr};
  std::thread loop_thread([&] {
    drive_with_fixes(rig, 500, true);  // warm-up
    AllocCounter counter;

    drive_with_fixes(rig, 500, false);  // motion-capture gap
    drive_with_fixes(rig, 200, true);

    for (const char* kind : {"nan_wheel", "inf_gyro", "stall", "read_error", "write_error"}) {
      (void)rig.inject(kind, 0.05, 1);
      drive_with_fixes(rig, 100, false);
      rig.loop->clear_fault();
      drive_with_fixes(rig, 100, false);
    }
    (void)rig.inject("out_of_range_wheel", 0.001, 0, 5.0);  // rejected by the drivetrain
    drive_with_fixes(rig, 100, false);
    rig.loop->clear_fault();
    drive_with_fixes(rig, 100, false);
    // Trips the odometry check; the encoder catching up at the end is an implausible jump.
    (void)rig.inject("frozen_encoder", 0.4, 1);
    drive_with_fixes(rig, 600, false);
    rig.loop->clear_fault();
    drive_with_fixes(rig, 100, false);
    (void)rig.inject("gyro_dropout", 0.1);  // falls back: no fault
    drive_with_fixes(rig, 200, false);
    after_sensor_faults = rig.state();

    rig.step(700);  // command timeout
    rig.command(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
    rig.step();
    rig.drive(1e9, 0.0, 1e9, 50);     // desaturated
    for (int c = 1; c <= 100; ++c) {  // flood
      requested.store(c, std::memory_order_release);
      while (done.load(std::memory_order_acquire) < c) std::this_thread::yield();
      rig.step();
    }

    rig.loop->request_localization_swap(failing.get(), "update_error");
    drive_with_fixes(rig, 100, false);  // fails after 50 updates
    retired[0] = rig.loop->take_retired_localization();
    rig.loop->request_localization_swap(working.get(), "raw_eg");
    rig.loop->clear_fault();
    drive_with_fixes(rig, 1, false);
    retired[1] = rig.loop->take_retired_localization();
    drive_with_fixes(rig, 200, false);
    counts = counter.counts();
  });
  loop_thread.join();
  quit.store(true, std::memory_order_release);
  producer.join();

  EXPECT_EQ(counts.allocations, 0U)
      << "first allocation: " << counts.first_allocation_bytes << " bytes";
  EXPECT_EQ(counts.deallocations, 0U);
  // The sequence went through its faults: five latched sensor/hardware faults, the encoder
  // jump, the frozen encoder and its catch-up jump, then a timeout, a rejected command and
  // the failing localization.
  EXPECT_EQ(after_sensor_faults.fault_count, 8U);
  EXPECT_EQ(after_sensor_faults.mode, LoopMode::kVelocity);
  const StateSnapshot last = rig.state();
  EXPECT_EQ(last.fault_count, 11U);
  EXPECT_EQ(last.mode, LoopMode::kVelocity);
  EXPECT_EQ(last.localization_swaps, 2U);
  EXPECT_STREQ(last.localization_plugin.data(), "raw_eg");
  EXPECT_EQ(retired[0], kalman);
  EXPECT_EQ(retired[1], failing.get());
  EXPECT_EQ(last.cycle,
            500U + 500 + 200 + 5 * 200 + 200 + 700 + 200 + 700 + 1 + 50 + 100 + 100 + 1 + 200);
}

// The recovery paths on the real plugins with motion limits on: a stall and its controlled
// stop, a clear refused and one accepted, a pose set, a swap rolled back by a refusing
// plugin, and the controlled stop before shutdown.
TEST(FaultAllocations, RecoveryWithMotionLimitsAllocatesNothingOnTheLoopThread) {
  RigOptions options;
  options.limits.linear_acceleration_mps2 = 1.0;
  options.limits.linear_jerk_mps3 = 10.0;
  options.limits.angular_acceleration_radps2 = 2.0;
  FaultRig rig(options);
  auto refusing = rig.make_localization("refuses_hand_over", "{}");
  HeapCounts counts;
  rt::LoopReply refused;
  rt::LoopReply cleared;
  rt::LoopReply posed;
  std::thread loop_thread([&] {
    rig.drive(0.5, 0.0, 0.2, 500);  // warm-up
    AllocCounter counter;
    rig.drive(0.5, 0.0, 0.2, 1000);
    (void)rig.inject("stall", 0.3);
    rig.drive(0.5, 0.0, 0.2, 100);
    rig.loop->request_clear(1);
    rig.drive(0.5, 0.0, 0.2, 1);
    (void)rig.loop->take_reply(refused);
    rig.drive(0.5, 0.0, 0.2, 600);
    rig.loop->request_clear(2);
    rig.drive(0.5, 0.0, 0.2, 1);
    (void)rig.loop->take_reply(cleared);
    PoseEstimate pose;
    pose.pose = {1.0, 2.0, 0.5};
    rig.loop->request_set_pose(pose, 3);
    rig.drive(0.5, 0.0, 0.2, 1);
    (void)rig.loop->take_reply(posed);
    (void)rig.loop->request_localization_swap(refusing.get(), "refuses_hand_over");
    rig.drive(0.5, 0.0, 0.2, 500);
    (void)rig.loop->take_retired_localization();
    rig.loop->request_controlled_stop(rig.t_s);
    rig.drive(0.5, 0.0, 0.2, 1000);
    counts = counter.counts();
  });
  loop_thread.join();
  EXPECT_EQ(counts.allocations, 0U)
      << "first allocation: " << counts.first_allocation_bytes << " bytes";
  EXPECT_EQ(counts.deallocations, 0U);
  EXPECT_FALSE(refused.ok);
  EXPECT_EQ(refused.fault, FaultCode::kHardwareError);
  EXPECT_TRUE(cleared.ok);
  EXPECT_TRUE(posed.ok);
  const StateSnapshot last = rig.state();
  EXPECT_TRUE(last.stopping);
  EXPECT_EQ(last.command_twist.vx_mps, 0.0);
  EXPECT_EQ(last.fault_count, 1U);
  EXPECT_STREQ(last.localization_plugin.data(), "raw_eg");
}

TEST(FaultAllocations, ThrowingPluginAllocatesTheException) {
  if (!test::malloc_is_counted()) GTEST_SKIP() << "malloc is not counted in sanitizer builds";
  RigOptions options;
  options.localization = "throws_update";
  options.localization_params = "{throw_after_cycles: 100}";
  FaultRig rig(options);
  HeapCounts counts;
  std::thread loop_thread([&] {
    rig.drive(0.3, 0.0, 0.0, 50);
    AllocCounter counter;
    rig.drive(0.3, 0.0, 0.0, 100);  // throws from the 101st update on
    counts = counter.counts();
  });
  loop_thread.join();
  EXPECT_EQ(rig.state().fault, FaultCode::kLocalizationError);
  EXPECT_GE(counts.allocations, 1U);
}

}  // namespace
}  // namespace swivel::faults
