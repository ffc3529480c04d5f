// SPDX-License-Identifier: Apache-2.0
#pragma once
// ROS time for stamps taken on the loop's clock. The loop stamps everything with
// CLOCK_MONOTONIC (steady, never stepped); ROS stamps are the system realtime clock
// (CLOCK_REALTIME, Unix time), which NTP or an administrator may step. Reading both clocks
// in every cycle would give stamps from two different instants; instead the offset
// realtime - monotonic is measured off the loop by bracketing one CLOCK_REALTIME read
// between two CLOCK_MONOTONIC reads (the narrowest of several brackets: the realtime read
// lies inside it, so its midpoint is within half its width), published through an atomic,
// and refreshed periodically by a non-real-time thread. A monotonic stamp t then maps to
// ROS time t + offset, consistently for every stamp taken between two refreshes. Both
// clocks run at the same NTP-disciplined rate, so the offset only changes when the realtime
// clock is stepped; a step shows up at the next refresh.

#include <atomic>
#include <cstdint>

namespace swivel::rt {

/// One measurement of CLOCK_REALTIME - CLOCK_MONOTONIC.
struct ClockOffsetMeasurement {
  std::int64_t offset_ns = 0;       ///< realtime - monotonic, ns
  std::int64_t uncertainty_ns = 0;  ///< half the width of the bracket it came from, ns
};

/// Not real-time: brackets a CLOCK_REALTIME read between two CLOCK_MONOTONIC reads `tries`
/// times (at least once) and keeps the narrowest bracket. No allocation, no lock.
ClockOffsetMeasurement measure_clock_offset(int tries = 16) noexcept;

/// The offset, shared between the thread that measures it and the threads that use it.
class ClockOffset {
 public:
  /// Measures once.
  ClockOffset() noexcept { refresh(); }

  /// Not real-time (see measure_clock_offset()). Measures and publishes a new offset.
  void refresh() noexcept;

  /// Any thread. Real-time safe (one atomic load). CLOCK_REALTIME - CLOCK_MONOTONIC, ns.
  [[nodiscard]] std::int64_t offset_ns() const noexcept {
    return offset_ns_.load(std::memory_order_acquire);
  }
  /// Any thread. The uncertainty of the newest measurement, ns (informative: it may belong
  /// to a measurement just before or after offset_ns()'s).
  [[nodiscard]] std::int64_t uncertainty_ns() const noexcept {
    return uncertainty_ns_.load(std::memory_order_acquire);
  }

  /// Any thread. Real-time safe. ROS time (Unix time, ns) of the monotonic time `monotonic_s`.
  [[nodiscard]] std::int64_t to_realtime_ns(double monotonic_s) const noexcept;

 private:
  std::atomic<std::int64_t> offset_ns_{0};
  std::atomic<std::int64_t> uncertainty_ns_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free);
};

/// ROS builtin_interfaces/Time of a Unix time in ns: whole seconds and nanoseconds in
/// [0, 1e9). Real-time safe; header-only so that the DDS bridge needs no runtime for it.
struct RosTime {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
};
inline RosTime to_ros_time(std::int64_t realtime_ns) noexcept {
  constexpr std::int64_t kNsPerS = 1'000'000'000;
  std::int64_t sec = realtime_ns / kNsPerS;
  std::int64_t nanosec = realtime_ns % kNsPerS;
  if (nanosec < 0) {
    nanosec += kNsPerS;
    --sec;
  }
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(nanosec)};
}

}  // namespace swivel::rt
