#include "swivel/rt/timing_stats.hpp"

#include <gtest/gtest.h>

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

TEST(LatencyHistogram, OverflowBucketReportsTheMaximum) {
  LatencyHistogram h;
  h.record(5'000'000);  // 5 ms, beyond the 2 ms of buckets
  h.record(3'000'000);
  EXPECT_DOUBLE_EQ(h.percentile_us(0.5), 5000.0);
  EXPECT_DOUBLE_EQ(h.max_us(), 5000.0);
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
