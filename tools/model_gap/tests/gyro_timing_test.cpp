// SPDX-License-Identifier: Apache-2.0
// The gyro column's meaning in time (swivel/run_log.hpp): swiveld records the reading at each
// row's time, `swivel-lab simulate` the mean over the row (declared). The sensor replay
// integrates each as what it is, so a log recorded the daemon's way gives the same answer as
// one written the simulator's way.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "gap_fixtures.hpp"
#include "swivel/model_gap/run_log_adapter.hpp"
#include "swivel/model_gap/sensor_replay.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {
namespace {

constexpr double kGyroBiasRadps = 0.004;
constexpr double kLeftScale = 0.998;
constexpr double kRightScale = 1.002;

// swiveld_record_test's figure: at rest, then turns both ways at several speeds, every change
// a step (the docent's nominal model has no `limits:`).
std::vector<testing::ScriptStep> figure() {
  return {{{0.0, 0.0, 0.0}, 5.0},   {{0.3, 0.0, 0.0}, 2.0}, {{0.3, 0.0, 0.6}, 2.0},
          {{0.15, 0.0, -0.5}, 2.5}, {{0.4, 0.0, 0.2}, 2.0}, {{0.0, 0.0, 0.8}, 1.5},
          {{0.25, 0.0, -0.3}, 2.0}};
}

RobotModel hidden_truth(const RobotModel& nominal) {
  RobotModel truth = nominal;
  truth.effects["gyro_bias"]["bias_rad_s"] = kGyroBiasRadps;
  truth.effects["wheel_radius"]["left_scale"] = kLeftScale;
  truth.effects["wheel_radius"]["right_scale"] = kRightScale;
  return truth;
}

double value_of(const FittedEffect& e, const std::string& key, double& sigma) {
  const auto it = std::find(e.keys.begin(), e.keys.end(), key);
  if (it == e.keys.end()) {
    ADD_FAILURE() << e.name << " has no " << key;
    sigma = 0.0;
    return std::nan("");
  }
  const auto i = static_cast<std::size_t>(it - e.keys.begin());
  sigma = e.sigmas[i];
  return e.values[i];
}

TEST(GyroTiming, TheRecorderWritesTheReadingAtEachRowUndeclared) {
  const RobotModel nominal = testing::robot("docent");
  const RunLog log = testing::record_like_swiveld(nominal, nominal, figure(), 8.0, 3);
  EXPECT_FALSE(log.header.gyro_mean_over_row);
  EXPECT_FALSE(to_run_data(log).gyro_mean_over_row);
  // At the first turn (t = 7 s, wz 0 -> 0.6 rad/s in one cycle) the row after the step reads
  // the new rate whole, where a row mean would hold only the part of the row after it.
  const auto row = static_cast<std::size_t>(std::llround(7.01 * 100.0));
  EXPECT_NEAR(log.samples[row].gyro_wz_radps, 0.6, 0.01);
  EXPECT_TRUE(testing::simulate_run(nominal, nominal, 2.0, 3).header.gyro_mean_over_row);
}

// Heading dead-reckoned from the gyro with the true model minus the true heading, per row:
// max |change over one row| and RMS over the run, rad. Noise-free sensors, so that what is
// left is the integration's.
struct HeadingError {
  double max_row_jump = 0.0;
  double rms = 0.0;
};

HeadingError heading_error(const RobotModel& nominal, const RobotModel& truth, const RunLog& log) {
  const RunData run = to_run_data(log);
  const SensorReplay replay(nominal, run, 1.0);
  std::vector<Pose2> path;
  replay.path(sim::resolve_plant(truth), TruthNuisance{}, path);
  HeadingError e;
  double previous = 0.0;
  double sum = 0.0;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const double error = path[k].yaw_rad - run.truth_yaw_rad[k];
    if (k > 0) e.max_row_jump = std::max(e.max_row_jump, std::abs(error - previous));
    previous = error;
    sum += error * error;
  }
  e.rms = std::sqrt(sum / static_cast<double>(path.size()));
  return e;
}

// The sensor replay integrates the readings at the rows by the trapezoid: across a step of
// the rate within a row (0.6 rad/s at the figure's first turn) the dead-reckoned heading is
// off by at most half the step times the row (3 mrad), where taking each reading as the
// row's mean leaves up to the whole (6 mrad) and all one way.
TEST(GyroTiming, ReadingsAtTheRowsIntegrateByTheTrapezoid) {
  const RobotModel nominal = testing::robot("docent");
  RobotModel truth = hidden_truth(nominal);
  truth.sensors.gyro.noise_rad_s = 0.0;
  truth.sensors.motion_capture.position_noise_m = 0.0;
  truth.sensors.motion_capture.yaw_noise_rad = 0.0;
  // Steps 3.7 ms into their rows, as the first corner (0.366 of 0.610 rad/s).
  const RunLog log = testing::record_like_swiveld(nominal, truth, figure(), 30.0, 5, 0.0037);
  const HeadingError trapezoid = heading_error(nominal, truth, log);
  constexpr double kLargestStepRadps = 1.3;  // -0.5 -> 0.8 rad/s
  EXPECT_LT(trapezoid.max_row_jump, 0.5 * kLargestStepRadps * 0.01);
  RunLog as_means = log;
  as_means.header.gyro_mean_over_row = true;  // what the replay assumed before
  const HeadingError means = heading_error(nominal, truth, as_means);
  EXPECT_GT(means.max_row_jump, 1.5 * trapezoid.max_row_jump);
  EXPECT_LT(trapezoid.rms, 0.5 * means.rms) << trapezoid.rms << " vs " << means.rms;
}

// A yaw rate that ramps up from a row (t = 0.1 s, 2 rad/s^2) and holds from halfway through a
// later row (0.21 s, 0.22 rad/s), read at 50 Hz rows: the trapezoid loses half the ramp's last
// rise times half a row (1e-4 rad) and keeps that lag while the rate holds. Readings taken
// as standing for the rate that much earlier (TruthNuisance::gyro_shift_s = -lag / rate) sum
// to the true heading again; a log of row means has no such nuisance.
TEST(GyroTiming, AShiftOfTheReadingsTakesTheLagOfRampsStartingOnRows) {
  const RobotModel nominal = testing::robot("docent");
  constexpr double kDt = 0.02;
  constexpr double kRampStart = 0.1;
  constexpr double kRampEnd = 0.21;
  constexpr double kSlope = 2.0;
  const auto rate = [](double t) {
    return kSlope * std::clamp(t - kRampStart, 0.0, kRampEnd - kRampStart);
  };
  const auto heading = [](double t) {  // the rate's integral
    const double ramp = std::clamp(t - kRampStart, 0.0, kRampEnd - kRampStart);
    return 0.5 * kSlope * ramp * ramp +
           kSlope * (kRampEnd - kRampStart) * std::max(0.0, t - kRampEnd);
  };
  RunData run;
  run.source = "ramp";
  run.wheel_rad.assign(2, {});
  for (int k = 0; k <= 150; ++k) {
    const double t = k * kDt;
    run.t_s.push_back(t);
    run.wheel_rad[0].push_back(0.0);
    run.wheel_rad[1].push_back(0.0);
    run.cmd_vx_mps.push_back(0.0);
    run.cmd_vy_mps.push_back(0.0);
    run.cmd_wz_radps.push_back(rate(t));
    run.gyro_radps.push_back(rate(t));
    run.truth_x_m.push_back(0.0);
    run.truth_y_m.push_back(0.0);
    run.truth_yaw_rad.push_back(heading(t));
  }
  run.truth_clock_shared = true;
  run.truth_frame_is_robot = true;
  const SensorReplay replay(nominal, run, 1.0);
  ASSERT_EQ(replay.nuisance().size(), 1U);
  EXPECT_EQ(replay.nuisance()[0].name, "truth.gyro_shift_s");
  EXPECT_NEAR(replay.nuisance()[0].upper, 0.5 * kDt, 1e-12);
  const sim::PlantParams plant = sim::resolve_plant(nominal);
  std::vector<Pose2> path;
  constexpr double kHold = kSlope * (kRampEnd - kRampStart);
  const double lag = 0.5 * (kSlope * 0.01) * 0.01;  // half the last rise (0.02) times half a row
  replay.path(plant, TruthNuisance{}, path);
  EXPECT_NEAR(heading(run.t_s.back()) - path.back().yaw_rad, lag, 1e-9);
  TruthNuisance shifted;
  shifted.gyro_shift_s = -lag / kHold;
  replay.path(plant, shifted, path);
  EXPECT_NEAR(path.back().yaw_rad, heading(run.t_s.back()), 1e-9);

  run.gyro_mean_over_row = true;
  EXPECT_TRUE(SensorReplay(nominal, run, 1.0).nuisance().empty());
}

// Issue: the default docent (no limits), a gyro bias and +-0.2 % wheel radii hidden in its true
// model, recorded as swiveld records; with gyro[k] taken as the row's mean the sensor question
// answered "unexplained: dyaw_gyro isolated jumps". The trapezoid of the readings names both
// effects: the bias within 3 sigma of the truth, each radius within a quarter of its hidden
// error (0.05 %) (on 8 seeds the left radius fell 1.1 to 4.4 of its stated sigmas from the truth,
// the bias within 0.7: the radii's stated sigma is too small, the workflow's to answer). Two
// minutes of the figure: on one minute the +-0.2 % radii are not significant yet.
TEST(GyroTiming, ARunRecordedLikeTheDaemonNamesGyroBiasAndWheelRadius) {
  const RobotModel nominal = testing::robot("docent");
  ASSERT_FALSE(nominal.limits.any());
  // The script's steps 3.7 ms into their rows, as in the recording.
  const RunLog log =
      testing::record_like_swiveld(nominal, hidden_truth(nominal), figure(), 120.0, 5, 0.0037);
  const GapResult r = analyse_gap(nominal, to_run_data(log));
  ASSERT_EQ(r.sensor.verdict, Verdict::kNamed) << r.sensor.summary;
  std::vector<std::string> names;
  for (const FittedEffect& e : r.sensor.named) names.push_back(e.name);
  std::sort(names.begin(), names.end());
  ASSERT_EQ(names, (std::vector<std::string>{"gyro_bias", "wheel_radius"})) << r.sensor.summary;
  for (const FittedEffect& e : r.sensor.named) {
    double sigma = 0.0;
    if (e.name == "gyro_bias") {
      const double bias = value_of(e, "bias_rad_s", sigma);
      EXPECT_LT(std::abs(bias - kGyroBiasRadps), 3.0 * sigma) << bias << " +- " << sigma;
    } else {
      constexpr double kRadiusTolerance = 0.25 * (kRightScale - kLeftScale) / 2.0;
      const double left = value_of(e, "left_scale", sigma);
      EXPECT_LT(std::abs(left - kLeftScale), kRadiusTolerance) << left << " +- " << sigma;
      const double right = value_of(e, "right_scale", sigma);
      EXPECT_LT(std::abs(right - kRightScale), kRadiusTolerance) << right << " +- " << sigma;
    }
  }
}

}  // namespace
}  // namespace swivel::model_gap
