// SPDX-License-Identifier: Apache-2.0
// PublishRateMeter on synthetic time: the achieved rate against min(configured, the loop's).

#include "swivel/dds/publish_rate_meter.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace swivel::dds {
namespace {

// Drives the meter for `seconds` at 1 ms steps with a loop of `loop_hz` and a publisher
// sending `publish_hz` states a second; returns the last change.
PublishRateMeter::Change run(PublishRateMeter& meter, double& now_s, std::uint64_t& cycle,
                             double& published, double seconds, double loop_hz, double publish_hz) {
  PublishRateMeter::Change last = PublishRateMeter::Change::kNone;
  for (int i = 0; i < static_cast<int>(seconds * 1000.0); ++i) {
    now_s += 0.001;
    cycle = static_cast<std::uint64_t>(now_s * loop_hz);
    published += publish_hz * 0.001;
    const auto change = meter.update(now_s, static_cast<std::uint64_t>(published), cycle);
    if (change != PublishRateMeter::Change::kNone) last = change;
  }
  return last;
}

TEST(PublishRateMeter, AtTheConfiguredRateIsNoShortfall) {
  PublishRateMeter meter(100.0);
  double now_s = 10.0;
  double published = 0.0;
  std::uint64_t cycle = 0;
  EXPECT_EQ(run(meter, now_s, cycle, published, 5.0, 1000.0, 100.0),
            PublishRateMeter::Change::kNone);
  EXPECT_NEAR(meter.achieved_hz(), 100.0, 1.0);
  EXPECT_DOUBLE_EQ(meter.attainable_hz(), 100.0);
  EXPECT_FALSE(meter.short_of_rate());
}

TEST(PublishRateMeter, ShortByMoreThanTheToleranceFallsShortAndRecovers) {
  PublishRateMeter meter(1000.0);
  double now_s = 10.0;
  double published = 0.0;
  std::uint64_t cycle = 0;
  EXPECT_EQ(run(meter, now_s, cycle, published, 5.0, 1000.0, 859.0),
            PublishRateMeter::Change::kFellShort);
  EXPECT_NEAR(meter.achieved_hz(), 859.0, 1.0);
  EXPECT_NEAR(meter.attainable_hz(), 1000.0, 1.0);
  EXPECT_TRUE(meter.short_of_rate());
  // Back at the rate: the verdict follows at once, the change is reported after the quiet
  // windows.
  EXPECT_EQ(run(meter, now_s, cycle, published, 5.0, 1000.0, 1000.0),
            PublishRateMeter::Change::kNone);
  EXPECT_FALSE(meter.short_of_rate());
  EXPECT_EQ(run(meter, now_s, cycle, published, 60.0, 1000.0, 1000.0),
            PublishRateMeter::Change::kRecovered);
}

// A rate that crosses the tolerance every window is reported once a minute, not every
// window.
TEST(PublishRateMeter, ARateAtTheToleranceIsReportedOnceAMinute) {
  PublishRateMeter meter(1000.0);
  double now_s = 10.0;
  double published = 0.0;
  std::uint64_t cycle = 0;
  int changes = 0;
  int short_windows = 0;
  for (int window = 0; window < 60; ++window) {  // 120 s
    const double rate = window % 2 == 0 ? 900.0 : 1000.0;
    if (run(meter, now_s, cycle, published, 2.0, 1000.0, rate) != PublishRateMeter::Change::kNone) {
      ++changes;
    }
    if (meter.short_of_rate()) ++short_windows;
  }
  EXPECT_GE(changes, 1);
  EXPECT_LE(changes, 4);         // 120 s: at most two changes a minute
  EXPECT_GE(short_windows, 20);  // the verdict itself follows every window
}

TEST(PublishRateMeter, WithinTheToleranceIsNoShortfall) {
  PublishRateMeter meter(1000.0);
  double now_s = 10.0;
  double published = 0.0;
  std::uint64_t cycle = 0;
  run(meter, now_s, cycle, published, 5.0, 1000.0, 960.0);
  EXPECT_FALSE(meter.short_of_rate());
}

// The publisher sends loop cycles: a loop slower than the publish rate caps what it can
// reach, and a stalled loop asks for nothing.
TEST(PublishRateMeter, ASlowerLoopCapsTheAttainableRate) {
  PublishRateMeter meter(1000.0);
  double now_s = 10.0;
  double published = 0.0;
  std::uint64_t cycle = 0;
  run(meter, now_s, cycle, published, 5.0, 250.0, 250.0);
  EXPECT_NEAR(meter.attainable_hz(), 250.0, 1.0);
  EXPECT_FALSE(meter.short_of_rate());

  PublishRateMeter stalled(100.0);
  now_s = 10.0;
  for (int i = 0; i < 5000; ++i) {
    now_s += 0.001;
    stalled.update(now_s, 7, 42);  // the same cycle, nothing new published
  }
  EXPECT_DOUBLE_EQ(stalled.attainable_hz(), 0.0);
  EXPECT_FALSE(stalled.short_of_rate());
}

TEST(PublishRateMeter, NoWindowBeforeTheLoopsFirstCycle) {
  PublishRateMeter meter(100.0);
  for (int i = 1; i <= 5000; ++i) meter.update(0.001 * i, 0, 0);
  EXPECT_DOUBLE_EQ(meter.achieved_hz(), 0.0);
  EXPECT_FALSE(meter.short_of_rate());
}

}  // namespace
}  // namespace swivel::dds
