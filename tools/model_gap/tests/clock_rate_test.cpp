// SPDX-License-Identifier: Apache-2.0
// A motion capture whose clock runs at its own rate (a log synchronised by hand at its start
// and end): the sensor question fits the rate beside the offset and names the robot's own
// effect, on a run made by the second robot generator (its own physics and motion capture),
// not by the replay's model.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "swivel/model_gap/run_log_adapter.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_log.hpp"
#include "swivel/second/second_robot.hpp"

namespace swivel::model_gap {
namespace {

struct Outcome {
  GapResult result;
  double rate = std::nan("");
  double rate_sigma = std::nan("");
  bool rate_fitted = false;
};

// A wide differential robot driving stop-and-go waypoints for 90 s at 50 Hz, its track 1.5 %
// wider than its model says, the motion capture 20 ms late on a clock 3 ms/s fast.
Outcome analyse(bool declare_same_rate) {
  second::RunSpec spec;
  spec.design = "wide_diff";
  spec.script = second::Script::kWaypoints;
  spec.row_rate_hz = 50.0;
  spec.duration_s = 90.0;
  spec.seed = 4242;
  second::set_truth(spec, "track_width.scale=1.015");
  second::set_truth(spec, "mocap.latency_s=0.02");
  second::set_truth(spec, "mocap.clock_rate=0.003");
  const second::GeneratedRun generated = second::generate(spec);
  std::string csv = generated.run_csv;
  if (declare_same_rate) {
    // The same log claiming a clock of the robot's rate: the rate is not fitted.
    csv.insert(csv.find("\nt,") + 1, "# truth_clock: same_rate\n");
  }
  std::istringstream in(csv);
  const RunData run = to_run_data(parse_run_log(in, "clock_rate.csv"));
  Outcome out;
  out.result = analyse_gap(parse_robot_model(generated.nominal_model_yaml, "wide_diff.yaml"), run);
  const GapResult& r = out.result;
  for (std::size_t i = 0; i < r.truth_names.size(); ++i) {
    if (r.truth_names[i] != "truth.clock_rate") continue;
    out.rate_fitted = true;
    out.rate = r.sensor.nuisance.at(i);
    out.rate_sigma = r.sensor.nuisance_sigmas.at(i);
  }
  return out;
}

// The track named, with at most the tyres' slip beside it (this generator's robot slips, as
// the benchmark allows); the track's fitted value, or NaN.
double named_track(const GapResult& r) {
  if (r.sensor.verdict != Verdict::kNamed) return std::nan("");
  double track = std::nan("");
  for (const FittedEffect& e : r.sensor.named) {
    if (e.name == "track_width" && e.values.size() == 1) {
      track = e.values[0];
    } else if (e.name != "slip") {
      return std::nan("");
    }
  }
  return track;
}

double track_sigma(const GapResult& r) {
  for (const FittedEffect& e : r.sensor.named) {
    if (e.name == "track_width") return e.sigmas.at(0);
  }
  return std::nan("");
}

TEST(ClockRate, ADriftingMotionCaptureClockIsFittedAndTheTrackNamed) {
  const Outcome o = analyse(false);
  const GapResult& r = o.result;
  ASSERT_TRUE(o.rate_fitted);
  EXPECT_NEAR(o.rate, 0.003, std::max(3.0 * o.rate_sigma, 1e-4))
      << "sigma " << o.rate_sigma << "; " << r.sensor.summary;
  EXPECT_LT(o.rate_sigma, 0.001);
  const double track = named_track(r);
  ASSERT_TRUE(std::isfinite(track)) << r.sensor.summary;
  EXPECT_NEAR(track, 1.015, 3.0 * track_sigma(r)) << r.sensor.summary;
  // The report quotes the rate with the other motion-capture nuisances.
  const std::vector<std::string> lines = truth_nuisance_lines(r);
  EXPECT_TRUE(std::ranges::any_of(
      lines, [](const std::string& l) { return l.find("clock rate") != std::string::npos; }));
}

TEST(ClockRate, WithoutTheRateTheSameRunIsNotExplainedByTheTrackAlone) {
  // The run's offset differs by 0.27 s between its start and end: one offset cannot hold
  // both, and the windows where the robot speeds up or stops disagree.
  const Outcome o = analyse(true);
  EXPECT_FALSE(o.rate_fitted);
  const double track = named_track(o.result);
  EXPECT_FALSE(std::abs(track - 1.015) < 3.0 * track_sigma(o.result)) << o.result.sensor.summary;
  // What one offset cannot hold goes into the noise, and the report says the noise is larger
  // than the model states.
  EXPECT_FALSE(o.result.sensor.noise_findings.empty()) << o.result.sensor.summary;
}

}  // namespace
}  // namespace swivel::model_gap
