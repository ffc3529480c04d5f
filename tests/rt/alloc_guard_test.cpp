// SPDX-License-Identifier: Apache-2.0
// Proves the loop's real-time rule "no heap operation on the loop thread" (STYLE.md): many
// cycles with a localization hot swap, faults and a command timeout in them (and, with
// external sensors configured, the gyro and motion-capture rings drained every cycle, their
// staleness checked, a stale gyro and its clear), counted by the allocation guard armed on
// the loop's thread only. The negative tests prove the guard
// would notice.

#include "alloc_guard.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <thread>
#include <vector>

#include "fake_plugins.hpp"
#include "swivel/rt/control_loop.hpp"
#include "swivel/rt/rt_log.hpp"  // copy_text

namespace swivel::rt {
namespace {

using test::AllocCounter;
using test::FakeDrivetrain;
using test::FakeHardware;
using test::FakeLocalization;
using test::HeapCounts;

constexpr int kWarmUpCycles = 1000;
constexpr int kArmedCycles = 12000;
constexpr int kSwapCycle = 6000;

// Per thread: two threads allocate at once in CountsOnlyTheArmedThread.
thread_local std::vector<int>* volatile t_sink = nullptr;

struct Outcome {
  HeapCounts counts;
  StateSnapshot last;
  std::uint64_t run_samples = 0;          // taken by the recording thread
  std::uint64_t run_sample_gaps = 0;      // jumps in their sequence numbers
  std::uint64_t run_samples_dropped = 0;  // the loop's count of samples a full ring refused
};

// Runs the scenario on a dedicated thread, as the loop thread would, and arms the guard there.
// With `external_sensors`, the sources are configured and fed: a gyro sample every 5 cycles
// (missing for 200 cycles from kGyroGapCycle: a stale fault, cleared at kGyroClearCycle) and
// a motion-capture pose every 10.
constexpr int kGyroGapCycle = 10000;
constexpr int kGyroClearCycle = 10300;

Outcome run_scenario(FakeLocalization& first, FakeLocalization& second, FakeHardware& hardware,
                     bool external_sensors = false) {
  FakeDrivetrain drivetrain;
  LoopOptions options;
  options.realtime = false;
  if (external_sensors) {
    for (SensorWatchOptions* w :
         {&options.external_sensors.gyro, &options.external_sensors.motion_capture}) {
      w->enabled = true;
      w->max_age_s = 0.05;
      w->startup_grace_s = 1.0;
      copy_text("rt/sensor: stale", w->stale_detail);
      copy_text("rt/sensor: silent", w->silent_detail);
    }
    // The gyro fed here is not the fake robot's turn rate.
    options.odometry_check.enabled = false;
  }
  // The twist window's fit and its covariance (a forward call per channel) run every cycle.
  options.wheel_encoder_resolution_rad = 2.0 * M_PI / 4096;
  options.steer_encoder_resolution_rad = 2.0 * M_PI / 4096;
  // Run samples for a recorder every 10th cycle, taken by a thread of their own.
  options.run_sample_rate_hz = 100.0;
  ControlLoop loop(options, hardware, drivetrain, first, "fake_a");
  Outcome outcome;
  std::atomic<bool> loop_done{false};
  std::thread recorder([&] {
    RunSample r;
    std::uint64_t last = 0;
    for (;;) {
      const bool done = loop_done.load(std::memory_order_acquire);
      while (loop.take_run_sample(r)) {
        if (r.sequence != last + 1) ++outcome.run_sample_gaps;
        last = r.sequence;
        ++outcome.run_samples;
      }
      if (done) return;
      std::this_thread::yield();
    }
  });
  std::thread loop_thread([&] {
    double now_s = 10.0;
    std::uint64_t sequence = 0;
    auto cycle = [&](int i, bool send_command) {
      now_s += loop.period_s();
      if (send_command && i % 20 == 0) {
        VelocityCommand c;
        c.twist = {0.3 + 0.1 * ((i / 1000) % 3), 0.0, ((i / 500) % 2) != 0 ? 0.4 : -0.2};
        c.received_s = now_s;
        c.sequence = ++sequence;
        loop.push_command(c);
      }
      if (external_sensors) {
        const bool gyro_gap = i >= kGyroGapCycle && i < kGyroGapCycle + 200;
        if (i % 5 == 0 && !gyro_gap) (void)loop.push_gyro({now_s, 0.1});
        if (i % 10 == 0) {
          MotionCaptureSample m;
          m.valid = true;
          m.stamp_s = now_s;
          m.pose = {0.01 * i, 0.0, 0.0};
          (void)loop.push_motion_capture(m, MotionCaptureSource::kWatched);
        }
        if (i == kGyroClearCycle) loop.clear_fault();
      }
      loop.run_cycle(now_s);
    };
    for (int i = 0; i < kWarmUpCycles; ++i) cycle(i, true);

    AllocCounter counter;
    for (int i = 0; i < kArmedCycles; ++i) {
      if (i == kSwapCycle) loop.request_localization_swap(&second, "fake_b");
      hardware.inject_nan = i >= 8000 && i < 8010;  // a sensor fault ...
      if (i == 8100) loop.clear_fault();            // ... cleared
      const bool commands = i < 9000 || i > 9700;   // a command timeout in between
      cycle(i, commands);
      if (i == kSwapCycle + 1) (void)loop.take_retired_localization();
    }
    outcome.counts = counter.counts();
  });
  loop_thread.join();
  loop_done.store(true, std::memory_order_release);
  recorder.join();
  outcome.run_samples_dropped = loop.run_samples_dropped();
  outcome.last = loop.latest();
  return outcome;
}

TEST(LoopAllocations, NoHeapOperationsOnTheLoopThreadAcrossASwap) {
  FakeHardware hardware;
  FakeLocalization first;
  FakeLocalization second;
  const Outcome outcome = run_scenario(first, second, hardware);

  EXPECT_EQ(outcome.counts.allocations, 0U)
      << "first allocation: " << outcome.counts.first_allocation_bytes << " bytes";
  EXPECT_EQ(outcome.counts.deallocations, 0U);
  // The scenario really went through its paths.
  EXPECT_EQ(outcome.last.cycle, static_cast<std::uint64_t>(kWarmUpCycles + kArmedCycles));
  EXPECT_EQ(outcome.last.localization_swaps, 1U);
  EXPECT_STREQ(outcome.last.localization_plugin.data(), "fake_b");
  EXPECT_EQ(outcome.last.fault_count, 2U);  // the sensor fault and the command timeout
  EXPECT_EQ(outcome.last.mode, LoopMode::kVelocity);
  EXPECT_GT(second.updates.load(), 5000U);
  EXPECT_TRUE(outcome.last.has_twist_covariance);
  EXPECT_GT(outcome.last.twist_covariance[0], 0.0);
  EXPECT_GT(outcome.last.odometry_twist.vx_mps, 0.25);
  // Every 10th cycle became a run sample. A recorder that fell behind (the cycles here run
  // back to back) loses samples to a full ring: counted by the loop and visible as jumps in
  // the sequence, never a blocked or allocating loop.
  EXPECT_EQ(outcome.run_samples + outcome.run_samples_dropped,
            static_cast<std::uint64_t>((kWarmUpCycles + kArmedCycles) / 10));
  EXPECT_EQ(outcome.run_samples_dropped == 0, outcome.run_sample_gaps == 0);
  EXPECT_GT(outcome.run_samples, 0U);
}

TEST(LoopAllocations, NoHeapOperationsWithExternalSensorsConfigured) {
  FakeHardware hardware;
  FakeLocalization first;
  FakeLocalization second;
  const Outcome outcome = run_scenario(first, second, hardware, true);

  EXPECT_EQ(outcome.counts.allocations, 0U)
      << "first allocation: " << outcome.counts.first_allocation_bytes << " bytes";
  EXPECT_EQ(outcome.counts.deallocations, 0U);
  EXPECT_EQ(outcome.last.cycle, static_cast<std::uint64_t>(kWarmUpCycles + kArmedCycles));
  // The sensor fault, the command timeout and the stale gyro, each cleared.
  EXPECT_EQ(outcome.last.fault_count, 3U);
  EXPECT_EQ(outcome.last.mode, LoopMode::kVelocity);
  EXPECT_EQ(outcome.last.gyro_wz_radps, 0.1);  // the external gyro, not the fake's
  EXPECT_GT(second.last_motion_capture_x_m.load(), 100.0);
}

TEST(LoopAllocations, GuardCatchesAPluginThatAllocates) {
  FakeHardware hardware;
  FakeLocalization first;
  FakeLocalization second;
  second.allocate_in_update = true;  // planted: a vector growing in update()
  const Outcome outcome = run_scenario(first, second, hardware);
  EXPECT_GE(outcome.counts.allocations, static_cast<std::uint64_t>(kArmedCycles - kSwapCycle));
  EXPECT_GT(outcome.counts.first_allocation_bytes, 0U);
}

TEST(LoopAllocations, GuardCatchesAPluginThatCallsMalloc) {
  if (!test::malloc_is_counted()) GTEST_SKIP() << "malloc is not counted in sanitizer builds";
  FakeHardware hardware;
  FakeLocalization first;
  FakeLocalization second;
  second.malloc_in_update = true;
  const Outcome outcome = run_scenario(first, second, hardware);
  // One malloc and one free per update() after the swap (a few faulty cycles skip update()).
  EXPECT_GE(outcome.counts.allocations, static_cast<std::uint64_t>(kArmedCycles - kSwapCycle) / 2);
  EXPECT_GE(outcome.counts.deallocations,
            static_cast<std::uint64_t>(kArmedCycles - kSwapCycle) / 2);
  EXPECT_EQ(outcome.counts.first_allocation_bytes, 64U);
}

TEST(AllocCounter, CountsOnlyTheArmedThread) {
  HeapCounts armed;
  std::thread other([] {
    for (int i = 0; i < 100; ++i) {
      t_sink = new std::vector<int>(16);
      delete t_sink;
    }
  });
  std::thread counted([&] {
    AllocCounter counter;
    t_sink = new std::vector<int>(16);  // two allocations: the vector and its storage
    delete t_sink;
    armed = counter.counts();
  });
  other.join();
  counted.join();
  EXPECT_EQ(armed.allocations, 2U);
  EXPECT_EQ(armed.deallocations, 2U);
  EXPECT_EQ(armed.first_allocation_bytes, sizeof(std::vector<int>));
}

}  // namespace
}  // namespace swivel::rt
