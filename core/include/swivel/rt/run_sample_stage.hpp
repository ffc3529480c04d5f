// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's last stage towards a recorder: one RunSample every LoopOptions::run_sample_rate_hz,
// through a lock-free SPSC ring, so that the recorder off the loop gets every sample and not
// just the newest state. Samples follow the clock, not a cycle count: one is due every period
// from the first cycle and taken at the first cycle within half a loop period of that, so that
// wake-up jitter does not move it to the next cycle; after a stall the schedule restarts
// rather than bursting. A full ring drops the sample (never blocks the loop); its sequence
// number is used up all the same, so the consumer sees the loss.
//
// The loop thread calls note_*() and publish(); one recording thread calls take(). Real-time
// safe, no allocation.

#include <atomic>
#include <cstdint>

#include "swivel/rt/run_sample.hpp"
#include "swivel/rt/spsc_ring.hpp"
#include "swivel/rt/state_snapshot.hpp"

namespace swivel::rt {

class RunSampleStage {
 public:
  /// Samples in the ring: 5 s at 100 Hz.
  static constexpr std::size_t kRingCapacity = 512;

  /// `sample_period_s`: the time between two samples, 0 for none; `loop_period_s` the loop's.
  RunSampleStage(double sample_period_s, double loop_period_s) noexcept
      : sample_period_s_(sample_period_s), loop_period_s_(loop_period_s) {}

  /// Loop thread. A motion-capture sample of this cycle: the newest one since the previous
  /// run sample stands in for the truth when the hardware has none.
  void note_motion_capture(const MotionCaptureSample& sample) noexcept { mocap_ = sample; }

  /// Loop thread. This cycle's target twist before the limits.
  void note_command(const Twist2& target) noexcept { command_ = target; }

  /// Loop thread, at the end of a cycle: hands `state` out as a sample when one is due.
  void publish(const StateSnapshot& state, double now_s) noexcept;

  /// The recording thread. The oldest sample not taken yet; false when there is none.
  bool take(RunSample& out) noexcept { return ring_.try_pop(out); }

  /// Any thread. Samples dropped because the ring was full.
  [[nodiscard]] std::uint64_t dropped() const noexcept {
    return dropped_.load(std::memory_order_relaxed);
  }

  /// Any thread. The time between two samples, s; 0 when there are none.
  [[nodiscard]] double period_s() const noexcept { return sample_period_s_; }

 private:
  void push(const StateSnapshot& state) noexcept;

  SpscRing<RunSample, kRingCapacity> ring_;
  std::atomic<std::uint64_t> dropped_{0};
  double sample_period_s_;
  double loop_period_s_;
  double next_s_ = 0.0;          // when the next one is due
  std::uint64_t sequence_ = 0;   // samples produced
  MotionCaptureSample mocap_{};  // newest one since the previous sample
  Twist2 command_{};
};

}  // namespace swivel::rt
