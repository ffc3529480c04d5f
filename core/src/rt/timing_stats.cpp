// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/timing_stats.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace swivel::rt {
namespace {

// Single writer: a load and a store are enough and avoid a locked read-modify-write.
void bump(std::atomic<std::uint64_t>& counter) noexcept {
  counter.store(counter.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
}

}  // namespace

// Above the linear range, a duration of `us` microseconds with its highest bit at `e`
// (2^e <= us < 2^(e+1), e >= 11) falls in sub-bucket (us >> (e - 6)) - 64 of doubling e - 11.
constexpr unsigned kLinearBits = 11;  // 2^11 = kLinearBuckets
constexpr unsigned kSubBits = 6;      // 2^6 = kSubBuckets
static_assert(LatencyHistogram::kLinearBuckets == 1U << kLinearBits);
static_assert(LatencyHistogram::kSubBuckets == 1U << kSubBits);

std::size_t LatencyHistogram::bucket_of(std::uint64_t us) noexcept {
  if (us < kLinearBuckets) return static_cast<std::size_t>(us);
  const auto e = static_cast<unsigned>(std::bit_width(us) - 1);
  const std::size_t doubling = e - kLinearBits;
  if (doubling >= kDoublings) return kBucketCount;  // overflow
  const std::size_t sub = static_cast<std::size_t>(us >> (e - kSubBits)) - kSubBuckets;
  return kLinearBuckets + doubling * kSubBuckets + sub;
}

double LatencyHistogram::upper_edge_us(std::size_t bucket) noexcept {
  if (bucket < kLinearBuckets) return static_cast<double>(bucket + 1);
  const std::size_t j = bucket - kLinearBuckets;
  const std::size_t doubling = j / kSubBuckets;
  const std::size_t sub = j % kSubBuckets;
  const auto width = static_cast<double>(std::uint64_t{1} << (doubling + kLinearBits - kSubBits));
  return static_cast<double>(kSubBuckets + sub + 1) * width;
}

void LatencyHistogram::record(std::int64_t duration_ns) noexcept {
  const std::int64_t ns = std::max<std::int64_t>(duration_ns, 0);
  bump(buckets_[bucket_of(static_cast<std::uint64_t>(ns / kBucketWidthNs))]);
  if (ns > max_ns_.load(std::memory_order_relaxed)) {
    max_ns_.store(ns, std::memory_order_relaxed);
  }
  bump(count_);
}

std::uint64_t LatencyHistogram::count() const noexcept {
  return count_.load(std::memory_order_relaxed);
}

double LatencyHistogram::max_us() const noexcept {
  return static_cast<double>(max_ns_.load(std::memory_order_relaxed)) / 1000.0;
}

double LatencyHistogram::percentile_us(double fraction) const noexcept {
  // Sum the buckets rather than trusting count_, which the writer may have bumped ahead of
  // (or behind) the bucket it belongs to.
  std::uint64_t total = 0;
  for (const auto& bucket : buckets_) total += bucket.load(std::memory_order_relaxed);
  if (total == 0) return 0.0;
  const double clamped = std::clamp(fraction, 0.0, 1.0);
  // Rank of the sample asked for; the epsilon keeps 0.999 * 10000 from rounding up to 9991.
  const auto rank = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::ceil(clamped * static_cast<double>(total) - 1e-9)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBucketCount; ++i) {
    seen += buckets_[i].load(std::memory_order_relaxed);
    if (seen >= rank) return std::min(upper_edge_us(i), max_us());
  }
  return max_us();
}

void LatencyHistogram::add(const LatencyHistogram& other) noexcept {
  for (std::size_t i = 0; i < buckets_.size(); ++i) {
    buckets_[i].store(buckets_[i].load(std::memory_order_relaxed) +
                          other.buckets_[i].load(std::memory_order_relaxed),
                      std::memory_order_relaxed);
  }
  count_.store(count_.load(std::memory_order_relaxed) + other.count(), std::memory_order_relaxed);
  const std::int64_t other_max = other.max_ns_.load(std::memory_order_relaxed);
  if (other_max > max_ns_.load(std::memory_order_relaxed)) {
    max_ns_.store(other_max, std::memory_order_relaxed);
  }
}

void LatencyHistogram::reset() noexcept {
  for (auto& bucket : buckets_) bucket.store(0, std::memory_order_relaxed);
  count_.store(0, std::memory_order_relaxed);
  max_ns_.store(0, std::memory_order_relaxed);
}

void TimingStats::record(std::int64_t lateness_ns, std::int64_t cycle_ns, bool overrun) noexcept {
  lateness_.record(lateness_ns);
  cycle_.record(cycle_ns);
  if (overrun) bump(overruns_);
}

TimingReport TimingStats::report() const noexcept {
  TimingReport r;
  r.period_us = period_s_ * 1e6;
  r.cycles = cycle_.count();
  r.overruns = overruns_.load(std::memory_order_relaxed);
  r.lateness_p50_us = lateness_.percentile_us(0.50);
  r.lateness_p99_us = lateness_.percentile_us(0.99);
  r.lateness_p999_us = lateness_.percentile_us(0.999);
  r.lateness_max_us = lateness_.max_us();
  r.cycle_p50_us = cycle_.percentile_us(0.50);
  r.cycle_p99_us = cycle_.percentile_us(0.99);
  r.cycle_p999_us = cycle_.percentile_us(0.999);
  r.cycle_max_us = cycle_.max_us();
  return r;
}

void TimingStats::reset() noexcept {
  lateness_.reset();
  cycle_.reset();
  overruns_.store(0, std::memory_order_relaxed);
}

}  // namespace swivel::rt
