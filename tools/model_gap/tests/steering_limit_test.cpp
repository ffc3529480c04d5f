// SPDX-License-Identifier: Apache-2.0
// Casters held at a steering rate limit or steering late (runs of the second robot generator,
// whose casters are servo-driven and whose tyres scrub by force): the sensor question does not
// compare the windows where they scrubbed, and a clean run shows no gap.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "second_runs.hpp"
#include "swivel/model_gap/run_data.hpp"
#include "swivel/model_gap/sensor_replay.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/second/validation_set.hpp"
#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {
namespace {

// A clean run of the first validation set (development data now).
SecondRun first_set_clean_run(std::size_t index) {
  const second::ValidationCase c = second::clean_case(second::kFirstValidationSeeds.clean, index);
  return load_second_run(c.spec, c.id);
}

std::size_t count_scrubbing_windows(const SensorReplay& sensors) {
  return static_cast<std::size_t>(std::ranges::count(sensors.scrubbing(), 1));
}

// cart4 (limit 5 rad/s) at 44 Hz on-the-spot turns: its sensor question was "unexplained" by
// jumps of 22-28 sigma in the two windows whose casters swung at the limit, where the casters
// disagreed about the motion 3.3 and 5.3 times as much as in the run's median window.
TEST(SteeringLimit, WindowsWhereCastersSteerAtTheStatedLimitAreNotCompared) {
  const SecondRun clean = first_set_clean_run(163);
  ASSERT_EQ(clean.model.modules.size(), 4U);
  ASSERT_TRUE(clean.model.limits.steering_rate_radps.has_value());
  const SensorReplay sensors(clean.model, clean.run, 1.0);
  const std::size_t w = sensors.windows().size();
  const std::size_t held = count_scrubbing_windows(sensors);
  EXPECT_GE(held, 2U);
  EXPECT_LE(held, w / 10) << "a run of turns is still mostly compared";

  std::vector<double> r;
  ASSERT_TRUE(sensors.residuals(sim::resolve_plant(clean.model), TruthNuisance{}, r));
  for (std::size_t j = 0; j < w; ++j) {
    if (sensors.scrubbing()[j] != 0) {
      EXPECT_TRUE(std::isnan(r[j])) << "window " << j;
    }
  }

  const GapResult gap = analyse_gap(clean.model, clean.run);
  EXPECT_EQ(gap.sensor.verdict, Verdict::kNoSignificantGap) << gap.sensor.summary;
  EXPECT_TRUE(std::ranges::any_of(
      gap.notes, [](const std::string& n) { return n.find("rate limit") != std::string::npos; }));
}

// A model that states no limit: the fastest the run steers stands for it, and the windows where
// the casters were held there and scrubbed are left out as with the stated limit.
TEST(SteeringLimit, AModelWithoutALimitTakesTheRunsFastestSteeringForIt) {
  SecondRun clean = first_set_clean_run(163);
  const SensorReplay stated(clean.model, clean.run, 1.0);
  clean.model.limits.steering_rate_radps.reset();
  const SensorReplay unstated(clean.model, clean.run, 1.0);
  for (std::size_t j = 0; j < stated.windows().size(); ++j) {
    if (stated.scrubbing()[j] != 0) {
      EXPECT_NE(unstated.scrubbing()[j], 0) << "window " << j;
    }
  }
  EXPECT_LE(count_scrubbing_windows(unstated), unstated.windows().size() / 10);
}

// The run standing still for twice as long after its last move: the windows at rest are not
// what a moving window's disagreement is measured against (were they, the median would be
// nothing, and every moving window would be left out), so the same windows are left out.
TEST(SteeringLimit, ALogThatMostlyStandsStillLeavesOutTheSameWindows) {
  const SecondRun clean = first_set_clean_run(163);
  RunData padded = clean.run;
  const std::size_t rows = padded.size();
  const double dt = (padded.t_s.back() - padded.t_s.front()) / static_cast<double>(rows - 1);
  for (std::size_t k = 0; k < 2 * rows; ++k) {
    padded.t_s.push_back(padded.t_s.back() + dt);
    for (std::vector<double>* zero :
         {&padded.cmd_vx_mps, &padded.cmd_vy_mps, &padded.cmd_wz_radps, &padded.gyro_radps}) {
      zero->push_back(0.0);
    }
    for (std::vector<double>* held :
         {&padded.truth_x_m, &padded.truth_y_m, &padded.truth_yaw_rad}) {
      held->push_back(held->back());
    }
    for (auto* columns : {&padded.wheel_rad, &padded.steer_rad}) {
      for (std::vector<double>& column : *columns) column.push_back(column.back());
    }
  }
  const SensorReplay moving(clean.model, clean.run, 1.0);
  const SensorReplay standing(clean.model, padded, 1.0);
  const std::size_t w = moving.windows().size();
  ASSERT_GT(standing.windows().size(), 2 * w) << "most windows stand still";
  ASSERT_GE(count_scrubbing_windows(moving), 2U);
  EXPECT_EQ(count_scrubbing_windows(standing), count_scrubbing_windows(moving));
  for (std::size_t j = 0; j < w; ++j) {
    EXPECT_EQ(standing.scrubbing()[j], moving.scrubbing()[j]) << "window " << j;
  }
}

// trike3 whose true steering limit is 2.35 rad/s where its model states 6 (a library run of the
// first validation set, development data now): its casters are held at 2.35 and scrub in
// windows whose steering reaches 0.9 of neither the stated limit nor the run's fastest (the
// servo overshoots to 2.85). Where the casters disagreed 5 and 12 times as much as in the
// median window the sensor question saw jumps of 11 sigma in dx; those windows are left out,
// and the sensor question finds no gap, as it should for a command-side effect.
TEST(SteeringLimit, CastersHeldAtALowerLimitThanStatedScrubAndAreNotCompared) {
  // The set's 67th case with one hidden effect (index 66, seed 7350067).
  const second::ValidationCase c =
      second::validation_set(second::kFirstValidationSeeds, 0, 67, 0).back();
  ASSERT_EQ(c.expected.size(), 1U);
  ASSERT_EQ(c.expected[0].effect, "steering_rate_limit");
  const SecondRun run = load_second_run(c.spec, c.id);
  const SensorReplay sensors(run.model, run.run, 1.0);
  EXPECT_GE(count_scrubbing_windows(sensors), 2U);
  EXPECT_LE(count_scrubbing_windows(sensors), sensors.windows().size() / 5);
  const GapResult gap = analyse_gap(run.model, run.run);
  EXPECT_EQ(gap.sensor.verdict, Verdict::kNoSignificantGap) << gap.sensor.summary;
}

// cart4 whose sensors report 0.072 s late (the fifth validation set's 30th case with one hidden
// effect, development data now). Its controller steers from those late angles, so the casters steer
// late and scrub in windows no stated limit explains: the casters disagree 2-3.5 times as much
// as in the median window there (clean runs stay within 1.4), and 4.8-5 times at the limit in
// windows 44 and 45, whose neighbour 46 keeps 2.9 times. Compared, window 46 kept jumps of 9
// noise sigmas after the latency was fitted, and the sensor question was "unexplained".
TEST(SteeringLimit, CastersSteeringLateAndTheScrubsTailAreNotCompared) {
  const HiddenEffectRun late =
      hidden_effect_run(second::kFifthValidationSeeds, 29, "sensor_latency");
  const SecondRun& run = late.run;
  const SensorReplay sensors(run.model, run.run, 1.0);
  for (const std::size_t j : {44U, 45U, 46U, 56U, 70U}) {
    EXPECT_NE(sensors.scrubbing()[j], 0) << "window " << j;
  }
  EXPECT_LE(count_scrubbing_windows(sensors), sensors.windows().size() / 5);
  const GapResult gap = analyse_gap(run.model, run.run);
  ASSERT_EQ(gap.sensor.verdict, Verdict::kNamed) << gap.sensor.summary;
  ASSERT_EQ(gap.sensor.named.size(), 1U);
  EXPECT_EQ(gap.sensor.named[0].name, "sensor_latency");
  EXPECT_LT(std::abs(gap.sensor.named[0].values.at(0) - late.truth),
            3.0 * gap.sensor.named[0].sigmas.at(0));
}

}  // namespace
}  // namespace swivel::model_gap
