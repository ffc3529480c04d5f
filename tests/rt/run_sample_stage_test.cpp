// SPDX-License-Identifier: Apache-2.0
// RunSampleStage: the loop's run samples for a recorder, on the clock and never blocking.

#include "swivel/rt/run_sample_stage.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace swivel::rt {
namespace {

constexpr double kLoopPeriodS = 0.001;

StateSnapshot state_at(std::uint64_t cycle, double stamp_s) {
  StateSnapshot s;
  s.cycle = cycle;
  s.stamp_s = stamp_s;
  s.estimate.pose = {0.1 * static_cast<double>(cycle), 0.0, 0.0};
  return s;
}

std::vector<RunSample> take_all(RunSampleStage& stage) {
  std::vector<RunSample> out;
  RunSample r;
  while (stage.take(r)) out.push_back(r);
  return out;
}

TEST(RunSampleStage, NoneWithoutARate) {
  RunSampleStage stage(0.0, kLoopPeriodS);
  for (int k = 0; k < 100; ++k) stage.publish(state_at(k, 0.001 * k), 0.001 * k);
  EXPECT_TRUE(take_all(stage).empty());
  EXPECT_EQ(stage.period_s(), 0.0);
}

TEST(RunSampleStage, FollowsTheClockWithJitterAndRestartsAfterAStall) {
  RunSampleStage stage(0.01, kLoopPeriodS);
  double t_s = 5.0;
  std::uint64_t cycle = 0;
  const auto run = [&](int cycles, double jitter_s) {
    for (int k = 0; k < cycles; ++k) {
      t_s += kLoopPeriodS;
      stage.publish(state_at(++cycle, t_s), t_s + ((k % 2) != 0 ? jitter_s : 0.0));
    }
  };
  run(95, 0.0004);  // waking late by less than half a period moves no sample
  std::vector<RunSample> samples = take_all(stage);
  ASSERT_EQ(samples.size(), 10U);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(samples[i].sequence, i + 1);
    EXPECT_EQ(samples[i].cycle, 1 + 10 * i);
  }
  t_s += 0.5;  // a stall: the schedule restarts instead of bursting
  run(20, 0.0);
  samples = take_all(stage);
  ASSERT_EQ(samples.size(), 2U);
  EXPECT_EQ(samples[1].cycle, samples[0].cycle + 10);
}

TEST(RunSampleStage, AFullRingDropsAndTheSequenceShowsIt) {
  RunSampleStage stage(kLoopPeriodS, kLoopPeriodS);
  const std::size_t produced = RunSampleStage::kRingCapacity + 3;
  for (std::size_t k = 1; k <= produced; ++k) {
    stage.publish(state_at(k, 0.001 * static_cast<double>(k)), 0.001 * static_cast<double>(k));
  }
  EXPECT_EQ(stage.dropped(), 3U);
  const std::vector<RunSample> samples = take_all(stage);
  ASSERT_EQ(samples.size(), RunSampleStage::kRingCapacity);
  stage.publish(state_at(produced + 1, 1.0), 1.0);
  RunSample next;
  ASSERT_TRUE(stage.take(next));
  EXPECT_EQ(next.sequence, produced + 1);  // the lost ones used their numbers up
}

TEST(RunSampleStage, MotionCaptureStandsInForTheTruthOnce) {
  RunSampleStage stage(kLoopPeriodS, kLoopPeriodS);
  MotionCaptureSample mocap;
  mocap.valid = true;
  mocap.stamp_s = 0.9995;
  mocap.pose = {1.0, 2.0, 0.5};
  stage.note_motion_capture(mocap);
  stage.note_command(Twist2{0.3, 0.0, 0.1});
  stage.publish(state_at(1, 1.0), 1.0);
  stage.publish(state_at(2, 1.001), 1.001);
  const std::vector<RunSample> samples = take_all(stage);
  ASSERT_EQ(samples.size(), 2U);
  EXPECT_TRUE(samples[0].has_truth);
  EXPECT_EQ(samples[0].truth.y_m, 2.0);
  EXPECT_EQ(samples[0].truth_stamp_s, 0.9995);
  EXPECT_EQ(samples[0].command_twist.vx_mps, 0.3);
  EXPECT_FALSE(samples[1].has_truth);  // nothing new since
}

}  // namespace
}  // namespace swivel::rt
