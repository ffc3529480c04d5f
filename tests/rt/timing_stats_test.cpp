// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/timing_stats.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>

namespace swivel::rt {
namespace {

TEST(LatencyHistogram, EmptyReportsZero) {
  LatencyHistogram h;
  EXPECT_EQ(h.count(), 0U);
  EXPECT_EQ(h.percentile_us(0.5), 0.0);
  EXPECT_EQ(h.max_us(), 0.0);
}

TEST(LatencyHistogram, PercentilesOfUniformSamplesAreBucketUpperEdges) {
  LatencyHistogram h;
  // 1000 samples at 0.5, 1.5, ..., 999.5 us: one per 1 us bucket.
  for (int i = 0; i < 1000; ++i) h.record(i * 1000 + 500);
  EXPECT_EQ(h.count(), 1000U);
  EXPECT_DOUBLE_EQ(h.percentile_us(0.50), 500.0);  // 500th sample lies in [499, 500) us
  EXPECT_DOUBLE_EQ(h.percentile_us(0.99), 990.0);
  EXPECT_DOUBLE_EQ(h.percentile_us(0.999), 999.0);
  EXPECT_DOUBLE_EQ(h.percentile_us(1.0), 999.5);  // capped at the exact maximum
  EXPECT_DOUBLE_EQ(h.max_us(), 999.5);
}

TEST(LatencyHistogram, RareOutliersShowOnlyInHighPercentiles) {
  LatencyHistogram h;
  for (int i = 0; i < 9990; ++i) h.record(10'200);  // 10.2 us
  for (int i = 0; i < 10; ++i) h.record(150'000);   // 150 us
  EXPECT_DOUBLE_EQ(h.percentile_us(0.50), 11.0);
  EXPECT_DOUBLE_EQ(h.percentile_us(0.99), 11.0);
  EXPECT_DOUBLE_EQ(h.percentile_us(0.999), 11.0);    // rank 9990 is still a 10.2 us sample
  EXPECT_DOUBLE_EQ(h.percentile_us(0.9991), 150.0);  // capped at the maximum (150 us)
  EXPECT_DOUBLE_EQ(h.max_us(), 150.0);
}

TEST(LatencyHistogram, MillisecondTailIsResolvedNotReportedAsTheMaximum) {
  LatencyHistogram h;
  // 100 000 samples as a loop under a hypervisor shows them: mostly 20 us, 0.5 % between 3
  // and 4 ms, and one stall of 250 ms.
  for (int i = 0; i < 99'499; ++i) h.record(20'000);
  for (int i = 0; i < 500; ++i) h.record(3'000'000 + i * 2'000);
  h.record(250'000'000);
  EXPECT_DOUBLE_EQ(h.max_us(), 250'000.0);
  // p99.9 is the 99 900th sample: the 401st of the tail, 3.8 ms; its bucket is 32 us wide.
  EXPECT_GE(h.percentile_us(0.999), 3800.0);
  EXPECT_LE(h.percentile_us(0.999), 3800.0 * (1.0 + 1.0 / 64));
  EXPECT_DOUBLE_EQ(h.percentile_us(0.99), 21.0);
}

TEST(LatencyHistogram, LogBucketsAreAtMostOneSixtyFourthWideUpTo16Seconds) {
  // Every duration lies in its bucket, whose upper edge is within 1/64 above it.
  for (std::uint64_t us = 1; us < (std::uint64_t{1} << 24); us = us * 3 / 2 + 1) {
    const std::size_t b = LatencyHistogram::bucket_of(us);
    ASSERT_LT(b, LatencyHistogram::kBucketCount) << us;
    EXPECT_GT(LatencyHistogram::upper_edge_us(b), static_cast<double>(us)) << us;
    EXPECT_LE(LatencyHistogram::upper_edge_us(b),
              std::max(static_cast<double>(us) + 1.0, static_cast<double>(us) * (1.0 + 1.0 / 64)))
        << us;
    if (b > 0) {
      EXPECT_LE(LatencyHistogram::upper_edge_us(b - 1), static_cast<double>(us)) << us;
    }
  }
  EXPECT_EQ(LatencyHistogram::bucket_of(std::uint64_t{1} << 24), LatencyHistogram::kBucketCount);
}

TEST(LatencyHistogram, BeyondSixteenSecondsTheOverflowBucketReportsTheMaximum) {
  LatencyHistogram h;
  h.record(20'000'000'000);  // 20 s
  h.record(30'000'000'000);
  EXPECT_DOUBLE_EQ(h.percentile_us(0.5), 30'000'000.0);
  EXPECT_DOUBLE_EQ(h.max_us(), 30'000'000.0);
}

TEST(LatencyHistogram, AddMergesSamplesAndMaximum) {
  LatencyHistogram a;
  LatencyHistogram b;
  for (int i = 0; i < 10; ++i) a.record(10'000);
  for (int i = 0; i < 30; ++i) b.record(50'000);
  b.record(5'000'000);
  a.add(b);
  EXPECT_EQ(a.count(), 41U);
  EXPECT_DOUBLE_EQ(a.percentile_us(0.2), 11.0);
  EXPECT_DOUBLE_EQ(a.percentile_us(0.5), 51.0);
  EXPECT_DOUBLE_EQ(a.max_us(), 5000.0);
  EXPECT_EQ(b.count(), 31U);
}

TEST(LatencyHistogram, NegativeDurationsCountAsZero) {
  LatencyHistogram h;
  h.record(-2000);
  EXPECT_EQ(h.count(), 1U);
  EXPECT_EQ(h.max_us(), 0.0);
  EXPECT_EQ(h.percentile_us(0.5), 0.0);
}

TEST(TimingStats, ReportCombinesBothHistogramsAndOverruns) {
  TimingStats stats(0.001);
  for (int i = 0; i < 100; ++i) stats.record(20'000 + i * 10, 5'000, false);
  stats.record(900'000, 1'200'000, true);
  const TimingReport r = stats.report();
  EXPECT_DOUBLE_EQ(r.period_us, 1000.0);
  EXPECT_EQ(r.cycles, 101U);
  EXPECT_EQ(r.overruns, 1U);
  EXPECT_DOUBLE_EQ(r.lateness_p50_us, 21.0);
  EXPECT_DOUBLE_EQ(r.lateness_max_us, 900.0);
  EXPECT_DOUBLE_EQ(r.lateness_p999_us, 900.0);
  EXPECT_DOUBLE_EQ(r.cycle_p50_us, 6.0);  // 5.0 us lies in the [5, 6) us bucket
  EXPECT_DOUBLE_EQ(r.cycle_max_us, 1200.0);
}

TEST(TimingStats, ResetEmptiesEverything) {
  TimingStats stats;
  stats.record(1000, 1000, true);
  stats.reset();
  const TimingReport r = stats.report();
  EXPECT_EQ(r.cycles, 0U);
  EXPECT_EQ(r.overruns, 0U);
  EXPECT_EQ(r.lateness_max_us, 0.0);
}

}  // namespace
}  // namespace swivel::rt
