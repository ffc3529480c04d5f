// SPDX-License-Identifier: Apache-2.0
#pragma once
// Loop timing statistics: fixed-bucket histograms of wake-up lateness and cycle time plus an
// overrun counter. The loop records with relaxed atomics and never allocates; any thread may
// read a report at any time (a report taken mid-cycle may be off by that one cycle).

#include <array>
#include <atomic>
#include <cstdint>

namespace swivel::rt {

/// Histogram of durations: 1 us buckets up to 2.048 ms, then log-spaced buckets (64 per
/// doubling, 1/64 = 1.6 % wide) up to 16.8 s, and one overflow bucket beyond; the exact
/// maximum is kept alongside. So the tail a loop shows under a hypervisor (milliseconds) is
/// resolved rather than reported as the maximum. One writer thread, any number of readers.
class LatencyHistogram {
 public:
  static constexpr std::int64_t kBucketWidthNs = 1000;  ///< of the linear buckets
  static constexpr std::size_t kLinearBuckets = 2048;   ///< [0, 2.048 ms) in 1 us steps
  static constexpr std::size_t kSubBuckets = 64;        ///< per doubling above that
  static constexpr std::size_t kDoublings = 13;         ///< 2.048 ms * 2^13 = 16.8 s
  static constexpr std::size_t kBucketCount =
      kLinearBuckets + kDoublings * kSubBuckets;  ///< regular buckets; one more overflows

  /// Writer only. Real-time safe (relaxed atomics, no allocation). Negative values count as 0.
  void record(std::int64_t duration_ns) noexcept;

  /// Any thread. Real-time safe. Samples recorded so far.
  [[nodiscard]] std::uint64_t count() const noexcept;

  /// Any thread (not meant for the loop: it walks every bucket). The smallest bucket upper
  /// edge below which at least `fraction` of the samples lie, in microseconds, capped at the
  /// maximum; the maximum when that bucket is the overflow one; 0 with no samples.
  [[nodiscard]] double percentile_us(double fraction) const noexcept;

  /// Any thread. Real-time safe. Largest sample, microseconds (exact, not bucketed).
  [[nodiscard]] double max_us() const noexcept;

  /// Not concurrent with record() on this histogram. Adds `other`'s samples (and maximum).
  void add(const LatencyHistogram& other) noexcept;

  /// Bucket index of a duration (microseconds, whole) and the upper edge of a bucket (us).
  [[nodiscard]] static std::size_t bucket_of(std::uint64_t us) noexcept;
  [[nodiscard]] static double upper_edge_us(std::size_t bucket) noexcept;

  /// Not concurrent with record(). Empties the histogram.
  void reset() noexcept;

 private:
  std::array<std::atomic<std::uint64_t>, kBucketCount + 1> buckets_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> max_ns_{0};
};

/// What report() returns: everything in microseconds.
struct TimingReport {
  double period_us = 0.0;
  std::uint64_t cycles = 0;      ///< cycles timed
  std::uint64_t overruns = 0;    ///< cycles that ended after their next deadline
  double lateness_p50_us = 0.0;  ///< wake-up time minus the deadline
  double lateness_p99_us = 0.0;
  double lateness_p999_us = 0.0;
  double lateness_max_us = 0.0;
  double cycle_p50_us = 0.0;  ///< time from wake-up to the end of the cycle's work
  double cycle_p99_us = 0.0;
  double cycle_p999_us = 0.0;
  double cycle_max_us = 0.0;
};

/// Timing of one periodic loop.
class TimingStats {
 public:
  explicit TimingStats(double period_s = 0.001) noexcept : period_s_(period_s) {}

  /// Loop thread only. Real-time safe. One cycle: how late it woke, how long its work took
  /// and whether it ended after the next deadline.
  void record(std::int64_t lateness_ns, std::int64_t cycle_ns, bool overrun) noexcept;

  /// Any thread; not real-time safe (walks every bucket). Percentiles as LatencyHistogram.
  [[nodiscard]] TimingReport report() const noexcept;

  [[nodiscard]] const LatencyHistogram& lateness() const noexcept { return lateness_; }
  [[nodiscard]] const LatencyHistogram& cycle_time() const noexcept { return cycle_; }

  /// Not concurrent with record().
  void reset() noexcept;

 private:
  double period_s_;
  LatencyHistogram lateness_;
  LatencyHistogram cycle_;
  std::atomic<std::uint64_t> overruns_{0};
};

}  // namespace swivel::rt
