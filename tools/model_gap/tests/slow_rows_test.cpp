// SPDX-License-Identifier: Apache-2.0
// 20 Hz rows and a 0.1 s sensor latency, on runs of the second robot generator (its own
// physics, sensors and motion capture): the sensor question names the latency within 5 % and
// the windows' gap shrinks at least threefold. And a latency of a row or two is not fitted
// short.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "second_runs.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/second/second_robot.hpp"

namespace swivel::model_gap {
namespace {

// A mixed-script run of `design` with rows at `rate_hz` and sensors `delay_s` late, analysed.
GapResult analyse_latency_run(const char* design, double rate_hz, double delay_s,
                              std::uint64_t seed, bool noise) {
  second::RunSpec spec;
  spec.design = design;
  spec.script = second::Script::kMixed;
  spec.row_rate_hz = rate_hz;
  spec.duration_s = 90.0;
  spec.seed = seed;
  spec.noise = noise;
  second::set_truth(spec, "sensor_latency.delay_s=" + std::to_string(delay_s));
  const SecondRun latency = load_second_run(spec, "latency_run");
  return analyse_gap(latency.model, latency.run);
}

TEST(SlowRows, A20HzRunNamesA100MillisecondLatencyWithinFivePercent) {
  for (const std::uint64_t seed : {1U, 2U, 3U}) {
    const GapResult r = analyse_latency_run("mid_diff", 20.0, 0.1, seed, true);
    ASSERT_EQ(r.sensor.verdict, Verdict::kNamed) << "seed " << seed << ": " << r.sensor.summary;
    ASSERT_EQ(r.sensor.named.size(), 1U) << r.sensor.summary;
    const FittedEffect& latency = r.sensor.named[0];
    ASSERT_EQ(latency.name, "sensor_latency") << r.sensor.summary;
    EXPECT_NEAR(latency.values.at(0), 0.1, 0.005) << "seed " << seed;
    // Every channel's gap over the windows shrinks at least threefold.
    for (const ChannelGap& c : r.sensor.channels) {
      ASSERT_GT(c.rms_after, 0.0) << c.info.name;
      EXPECT_GE(c.rms_before / c.rms_after, 3.0) << "seed " << seed << " " << c.info.name;
    }
  }
}

// Rows at 25 Hz, sensors 68 ms late, no noise: what is left is the workflow's own bias. The
// motion capture's noise is averaged into each window's end along a path; along the nominal
// dead reckoning, which shows the motion 68 ms late, the latency came out 0.8-1.7 % short
// (67.1, 67.4 and 66.9 ms); along each replay's own path, within 0.25 %.
TEST(SlowRows, ALatencyOfARowOrTwoIsNotFittedShort) {
  constexpr double kDelayS = 0.068;
  for (const std::uint64_t seed : {1U, 2U, 3U}) {
    const GapResult r = analyse_latency_run("mini_diff", 25.0, kDelayS, seed, false);
    ASSERT_EQ(r.sensor.verdict, Verdict::kNamed) << "seed " << seed << ": " << r.sensor.summary;
    ASSERT_EQ(r.sensor.named.size(), 1U) << r.sensor.summary;
    ASSERT_EQ(r.sensor.named[0].name, "sensor_latency") << r.sensor.summary;
    EXPECT_NEAR(r.sensor.named[0].values.at(0), kDelayS, 0.005 * kDelayS) << "seed " << seed;
  }
}

}  // namespace
}  // namespace swivel::model_gap
