// SPDX-License-Identifier: Apache-2.0
// The model-gap workflow on a real robot's logs: OptiOdom's differential robot (three runs
// vendored under tests/data/optiodom, MIT), imported with the shipped map and analysed with the
// shipped nominal model. No gyro, no commands, a motion-capture body not on the robot's axis,
// 19.5 Hz rows: what every real log brings. And a steering log wrapped to (-pi, pi] gives the
// same verdicts as its unwrapped twin.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "gap_fixtures.hpp"
#include "swivel/model_gap/cross_run.hpp"
#include "swivel/model_gap/fold_effects.hpp"
#include "swivel/model_gap/judge.hpp"
#include "swivel/model_gap/run_log_adapter.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/pose_math.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_import/run_import.hpp"

namespace swivel::model_gap {
namespace {

std::string source_dir() {
  const char* env = std::getenv("SWIVEL_SOURCE_DIR");
  return env != nullptr ? env : SWIVEL_SOURCE_DIR_FALLBACK;
}

RunData import_vendored(const std::string& run) {
  const std::string dir = source_dir();
  const run_import::ImportMap map =
      run_import::load_import_map(dir + "/config/import/optiodom_diff.yaml");
  const std::string path = dir + "/tests/data/optiodom/" + run + ".csv";
  std::ifstream in(path);
  return to_run_data(run_import::import_run(in, path, map));
}

RobotModel optiodom_model() {
  return load_robot_model(source_dir() + "/config/robots/optiodom_diff.yaml");
}

double nuisance(const GapResult& r, const std::string& name, double* sigma) {
  for (std::size_t i = 0; i < r.truth_names.size(); ++i) {
    if (r.truth_names[i] != name) continue;
    *sigma = r.sensor.nuisance_sigmas.at(i);
    return r.sensor.nuisance.at(i);
  }
  ADD_FAILURE() << "no nuisance " << name;
  return std::nan("");
}

// The authors' calibration of this robot (OptiOdom data.xlsx, sheet diff-Sousa): track
// 0.2010-0.2017 m, wheel diameter 0.0835-0.0838 m. With the nominal radii kept, a track-width
// scale fitted here is the ratio of effective track to wheel radius against the nominal one:
// (L / r) / (0.2 / 0.042) in 1.0074 .. 1.0146.
constexpr double kAuthorsTrackScaleLow = (0.2010 / 0.0419) / (0.2 / 0.042);
constexpr double kAuthorsTrackScaleHigh = (0.2017 / 0.04175) / (0.2 / 0.042);

TEST(RealRun, FreeDrivingRunReportsTheTrackedBodysYawOffsetAndAnAuthorsTrack) {
  const RunData run = import_vendored("030120210001_run-01");
  ASSERT_FALSE(run.has_gyro);
  ASSERT_FALSE(run.has_commands);
  const GapResult r = analyse_gap(optiodom_model(), run);
  EXPECT_FALSE(r.command_assessed);
  EXPECT_NE(r.sensor.verdict, Verdict::kUnexplained) << r.sensor.summary;
  // The straight stretches show the tracked body turned against the direction of travel by
  // 4-10 mrad (every straight-driving OptiOdom run does), known to well under a milliradian
  // per milliradian of offset.
  double sigma = 0.0;
  const double yaw = nuisance(r, "truth.yaw_offset_rad", &sigma);
  EXPECT_LT(yaw, -0.004);
  EXPECT_GT(yaw, -0.012);
  EXPECT_LT(sigma, 0.002);
  // No gyro: no gyro channel, no gyro candidate, and the report says so.
  for (const ChannelGap& c : r.sensor.channels)
    EXPECT_EQ(c.info.name.find("gyro"), std::string::npos);
  for (const CandidateScore& c : r.sensor.candidates) {
    for (const std::string& e : c.effects) EXPECT_EQ(e.find("gyro"), std::string::npos);
  }
  ASSERT_FALSE(r.notes.empty());
  for (const FittedEffect& e : r.sensor.named) {
    if (e.name != "track_width") continue;
    EXPECT_GT(e.values[0] + 2.0 * e.sigmas[0], kAuthorsTrackScaleLow);
    EXPECT_LT(e.values[0] - 2.0 * e.sigmas[0], kAuthorsTrackScaleHigh);
  }
}

TEST(RealRun, ShortCircularRunsAreAnalysedWithoutAnUnexplainedVerdict) {
  const RobotModel model = optiodom_model();
  std::vector<RunData> runs;
  for (const char* name : {"231220200157_run-01", "231220200157_run-02"}) {
    runs.push_back(import_vendored(name));
    const GapResult r = analyse_gap(model, runs.back());
    EXPECT_NE(r.sensor.verdict, Verdict::kUnexplained) << name << ": " << r.sensor.summary;
  }
  // Across the two: each judged on the other, nothing skipped, ratios finite.
  const CrossRunResult cross = cross_validate(model, runs, {});
  EXPECT_TRUE(cross.skipped.empty());
  ASSERT_EQ(cross.pairs, 2U);
  for (const FitRun& f : cross.fits) {
    for (double q : f.ratio) EXPECT_TRUE(std::isfinite(q) && q > 0.0);
  }
}

// June circle 250620202251 run 9 names nothing: its track width changes a 1 s window by a
// fraction of the noise, but over a 100 s circle it turns the path by degrees. Calibrated (a
// parameter of the robot's own model, not a missing effect), the track comes out wider than
// nominal as the authors' calibration has it, and predicts the session's next circle, which the
// fit never saw, better than the nominal model.
TEST(RealRun, ACalibratedTrackFromOneCirclePredictsTheSessionsOtherCircle) {
  const RobotModel model = optiodom_model();
  const std::vector<RunData> runs = {import_vendored("250620202251_run-09"),
                                     import_vendored("250620202251_run-10")};
  const CrossRunResult cross = cross_validate(model, runs, {});
  ASSERT_EQ(cross.fits.size(), 2U);
  const FitRun& fit = cross.fits[0];
  EXPECT_EQ(fit.verdict, Verdict::kNoSignificantGap) << fit.summary;
  EXPECT_TRUE(fit.named.empty());
  ASSERT_EQ(fit.calibrated.size(), 1U) << fit.summary;
  const FittedEffect& track = fit.calibrated[0];
  ASSERT_EQ(track.name, "track_width");
  EXPECT_GE(track.z, 3.0);
  EXPECT_GT(track.values[0], 1.0 + 2.0 * track.sigmas[0]);
  EXPECT_GT(track.values[0], kAuthorsTrackScaleLow - 3.0 * track.sigmas[0]);
  EXPECT_LT(track.values[0], kAuthorsTrackScaleHigh + 3.0 * track.sigmas[0]);
  // What the daemon would load: the track folded into the robot's own parameter.
  EXPECT_NEAR(fold_effects(fit.fitted).model.differential.track_width_m,
              model.differential.track_width_m * track.values[0], 1e-9);
  ASSERT_EQ(fit.ratio.size(), 1U);
  EXPECT_LT(fit.ratio[0], 0.7) << "held-out RMS position gap " << fit.nominal_rms_m[0] << " m -> "
                               << fit.fitted_rms_m[0] << " m";
}

// Fitted on three runs together (a free run names a track, a June circle calibrates one, a
// December circle fixes nothing; a value two runs give is pooled at its weighted mean, one
// run's alone is left out), the model is judged on a December circle none of them is: its gap
// shrinks against the nominal model's.
TEST(RealRun, APooledModelIsJudgedOnARunItWasNotFittedOn) {
  const RobotModel model = optiodom_model();
  const std::vector<RunData> fit_runs = {import_vendored("030120210001_run-01"),
                                         import_vendored("250620202251_run-09"),
                                         import_vendored("231220200157_run-01")};
  const CrossRunResult cross = cross_validate(model, fit_runs, {});
  ASSERT_EQ(cross.pooled_from.size(), 1U);
  EXPECT_EQ(cross.pooled_from[0].rfind("track_width.scale = 1.01", 0), 0U) << cross.pooled_from[0];
  const double scale = cross.pooled.effects.at("track_width").at("scale");
  EXPECT_GT(scale, kAuthorsTrackScaleLow);
  EXPECT_LT(scale, kAuthorsTrackScaleHigh);
  for (const std::string& left : cross.pooled_left_out)
    EXPECT_NE(left.find(": 1 run"), std::string::npos) << left;
  // Written for the daemon: the track folded into the robot's own parameter.
  const std::string dir = ::testing::TempDir() + "/pooled_cross_run";
  write_cross_run_report(cross, model, dir);
  const RobotModel written = load_robot_model(dir + "/model_pooled.yaml");
  EXPECT_TRUE(written.effects.empty());
  EXPECT_NEAR(written.differential.track_width_m, model.differential.track_width_m * scale, 1e-12);

  const RunData unseen = import_vendored("231220200157_run-02");
  const JudgeResult judged =
      judge_models({model, cross.pooled}, {"nominal", "pooled"}, {unseen}, {});
  ASSERT_EQ(judged.runs.size(), 1U);
  ASSERT_EQ(judged.groups.size(), 2U);  // the runs' folder, then all
  EXPECT_EQ(judged.groups.back().group, "all");
  const std::vector<double>& gap = judged.runs[0].rms_position_m;
  EXPECT_LT(gap[1], 0.7 * gap[0]) << "RMS position gap " << gap[0] << " m -> " << gap[1] << " m";
  EXPECT_DOUBLE_EQ(judged.groups.back().median_ratio[1], gap[1] / gap[0]);
}

// Two UMBmark squares of June session 230620202258, a session the workflow was judged on and
// never developed on (tools/lab/GAP.md section 8): driving straight and turning on the spot,
// they fix the wheel radii the circles cannot. One names them, the other calibrates them; both
// agree with each other and with the authors' calibrated diameters (0.0835-0.0838 m, 0.994-0.998
// of the nominal 0.084 m), the right wheel the smaller, and each run's model shrinks the
// other's gap. (The session's metadata states Li 0.205 m and Di 0.085 m; the shipped nominal
// model, 0.2 m and 0.084 m, is used as for every run.)
TEST(RealRun, SquaresOfASessionNeverDevelopedOnFixBothWheelRadiiAsTheAuthorsDid) {
  constexpr double kAuthorsRadiusScaleLow = 0.0835 / 0.084;
  constexpr double kAuthorsRadiusScaleHigh = 0.0838 / 0.084;
  const RobotModel model = optiodom_model();
  const std::vector<RunData> runs = {import_vendored("230620202258_run-02"),
                                     import_vendored("230620202258_run-03")};
  const CrossRunResult cross = cross_validate(model, runs, {});
  ASSERT_EQ(cross.fits.size(), 2U);
  EXPECT_EQ(cross.unexplained, 0U);
  for (const FitRun& fit : cross.fits) {
    SCOPED_TRACE(fit.run);
    const std::vector<FittedEffect>& effects = fit.named.empty() ? fit.calibrated : fit.named;
    ASSERT_EQ(effects.size(), 1U) << fit.summary;
    const FittedEffect& radii = effects[0];
    ASSERT_EQ(radii.name, "wheel_radius");
    ASSERT_EQ(radii.keys, (std::vector<std::string>{"left_scale", "right_scale"}));
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_GT(radii.values[i], kAuthorsRadiusScaleLow - 3.0 * radii.sigmas[i]);
      EXPECT_LT(radii.values[i], kAuthorsRadiusScaleHigh + 3.0 * radii.sigmas[i]);
    }
    EXPECT_LT(radii.values[1], radii.values[0]);
    ASSERT_EQ(fit.ratio.size(), 1U);
    EXPECT_LT(fit.ratio[0], 0.95) << fit.nominal_rms_m[0] << " m -> " << fit.fitted_rms_m[0]
                                  << " m";
  }
  EXPECT_EQ(cross.named + cross.calibrated, 2U);
  for (const ParameterAgreement& a : cross.agreement) {
    EXPECT_EQ(a.values.size(), 2U) << a.name;
    EXPECT_DOUBLE_EQ(a.within_2_sigma, 1.0) << a.name;
  }
}

// A track fitted alone holds what wheel radii would take beside it: pooled from different runs,
// a track from one and radii from others would count that twice. The pooled model takes the
// set of effects most runs fixed (both squares: the radii) and leaves the free run's track out.
TEST(RealRun, ThePooledModelDoesNotMixEffectsFittedInDifferentSets) {
  const RobotModel model = optiodom_model();
  const std::vector<RunData> runs = {import_vendored("030120210001_run-01"),
                                     import_vendored("230620202258_run-02"),
                                     import_vendored("230620202258_run-03")};
  const CrossRunResult cross = cross_validate(model, runs, {});
  EXPECT_EQ(cross.pooled.effects.count("track_width"), 0U);
  ASSERT_EQ(cross.pooled.effects.count("wheel_radius"), 1U);
  EXPECT_EQ(cross.pooled.effects.at("wheel_radius").size(), 2U);
  ASSERT_EQ(cross.pooled_left_out.size(), 1U);
  EXPECT_EQ(cross.pooled_left_out[0], "track_width: 1 run, not the set most runs fixed");
  // The agreement table still shows every parameter any run fixed.
  EXPECT_EQ(cross.agreement.size(), 3U);
}

bool scores_effect(const QuestionResult& q, const std::string& effect) {
  for (const CandidateScore& c : q.candidates) {
    for (const std::string& e : c.effects)
      if (e == effect) return true;
  }
  return false;
}

bool has_note(const GapResult& r, const std::string& part) {
  return std::ranges::any_of(
      r.notes, [&part](const std::string& n) { return n.find(part) != std::string::npos; });
}

// On one circle a common wheel-radius scale moves the tracked body's circle as its lever arm
// does, and a left/right difference turns it as a track does: such runs named radii 1-5 % below
// the authors' calibration from their few windows of starting and stopping. They are not
// offered there; a run that also drives straight keeps them.
TEST(RealRun, RunsOfOneCircleDoNotOfferWheelRadii) {
  const RobotModel model = optiodom_model();
  for (const char* name : {"231220200157_run-01", "231220200157_run-02"}) {
    const GapResult r = analyse_gap(model, import_vendored(name));
    EXPECT_FALSE(scores_effect(r.sensor, "wheel_radius")) << name;
    EXPECT_TRUE(has_note(r, "drives one circle")) << name;
  }
  const GapResult free = analyse_gap(model, import_vendored("030120210001_run-01"));
  EXPECT_TRUE(scores_effect(free.sensor, "wheel_radius"));
  EXPECT_FALSE(has_note(free, "drives one circle"));
}

// June circle 250620202251 run 10: the motion capture leads the encoders by about 0.15 s while
// the robot speeds up at the start and agrees with them at the end, as a log synchronised by
// hand at both ends does. With one clock offset its first three windows were isolated jumps
// (unexplained, while the window ends were averaged along the nominal path); the clock rate
// takes them, and agrees with the run's metadata: its spans on the two clocks (gt 5.79-108.5 s,
// odometry 0-100.55 s) stand 1.67 ms/s below the median ratio of the 61 development runs
// (1.02319), so the motion capture's offset grows by that much. That median is a reference of
// its own (the 61 runs' fitted rates stand 0.9 ms/s above their metadata's on average), so the
// rate is checked against the metadata where the reference cancels: its difference from the
// rates of the session's runs 04, 05 and 09 (metadata -1.70, +0.21 and -0.65 ms/s). With the
// windows' ends averaged along the nominal path the rates came out shrunk towards zero (run 04's
// difference 1.79 ms/s for the metadata's 3.37).
double clock_rate_ms_per_s(const GapResult& r, double* sigma) {
  EXPECT_NE(r.sensor.verdict, Verdict::kUnexplained) << r.sensor.summary;
  const double rate = nuisance(r, "truth.clock_rate", sigma);
  *sigma *= 1e3;
  return rate * 1e3;
}

double metadata_rate_ms_per_s(double gt_start, double gt_end, double odo_end) {
  return 1e3 * (1.0 - ((gt_end - gt_start) / odo_end) / 1.02319);
}

TEST(RealRun, AHandSynchronisedStartIsAClockRateNotAnUnexplainedJump) {
  const RobotModel model = optiodom_model();
  RunData run = import_vendored("250620202251_run-10");
  const GapResult with_rate = analyse_gap(model, run);
  double sigma = 0.0;
  const double rate = clock_rate_ms_per_s(with_rate, &sigma);
  EXPECT_GT(rate, 3.0 * sigma) << "sigma " << sigma;
  const double from_metadata = metadata_rate_ms_per_s(5.79, 108.5, 100.55);
  struct Other {
    const char* name;
    double metadata_ms_per_s;
  };
  for (const Other& other :
       {Other{"250620202251_run-04", metadata_rate_ms_per_s(5.09, 108.3, 100.7)},
        Other{"250620202251_run-05", metadata_rate_ms_per_s(4.24, 107.1, 100.55)},
        Other{"250620202251_run-09", metadata_rate_ms_per_s(8.5, 111.5, 100.6)}}) {
    double other_sigma = 0.0;
    const double other_rate =
        clock_rate_ms_per_s(analyse_gap(model, import_vendored(other.name)), &other_sigma);
    EXPECT_NEAR(rate - other_rate, from_metadata - other.metadata_ms_per_s,
                3.0 * std::hypot(sigma, other_sigma))
        << other.name;
  }
  // Declared to keep one rate, the drift the rate took is left in the windows: their noise in
  // dx is reported well above what it is with the rate (4.5 and 2.1 times the stated).
  run.truth_clock_same_rate = true;
  const GapResult one_offset = analyse_gap(model, run);
  const auto dx_noise = [](const GapResult& r) {
    for (const NoiseFinding& f : r.sensor.noise_findings)
      if (f.channel.name == "dead_reckoning.dx_m") return f.ratio;
    return 1.0;
  };
  EXPECT_GT(dx_noise(one_offset), 1.5 * dx_noise(with_rate)) << one_offset.sensor.summary;
}

TEST(RealRun, ARunTooShortForItsWindowsSaysSo) {
  RunData run = import_vendored("231220200157_run-01");
  const std::size_t keep = 150;  // under 8 s of rows
  run.t_s.resize(keep);
  for (auto* v : {&run.cmd_vx_mps, &run.cmd_vy_mps, &run.cmd_wz_radps, &run.gyro_radps,
                  &run.truth_x_m, &run.truth_y_m, &run.truth_yaw_rad})
    v->resize(keep);
  for (auto& w : run.wheel_rad) w.resize(keep);
  try {
    (void)analyse_gap(optiodom_model(), run);
    FAIL() << "a run of " << keep << " rows was analysed";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the workflow needs at least 10"), std::string::npos)
        << e.what();
  }
  // Judged among others, it is set aside with that reason and the rest are judged.
  const RobotModel model = optiodom_model();
  const JudgeResult judged =
      judge_models({model}, {"nominal"}, {run, import_vendored("231220200157_run-02")}, {});
  EXPECT_EQ(judged.runs.size(), 1U);
  ASSERT_EQ(judged.skipped.size(), 1U);
  EXPECT_NE(judged.skipped[0].find("the workflow needs at least 10"), std::string::npos)
      << judged.skipped[0];
}

// An absolute steering encoder reports (-pi, pi]: a caster that turns round crosses +-pi. The
// same run with its steering wrapped must give the same verdicts and values.
TEST(WrappedSteering, SameVerdictsAsUnwrapped) {
  using testing::robot;
  const RobotModel nominal = robot("swpc4");
  RobotModel truth = nominal;
  truth.effects["caster_offset"] = {{"module_1_scale", 1.1},
                                    {"module_2_scale", 1.1},
                                    {"module_3_scale", 1.1},
                                    {"module_4_scale", 1.1}};
  RunLog log = testing::simulate_run(nominal, truth, 60.0, 5);
  // Turn every caster's encoder by a constant so that its angles cross +-pi on the way.
  constexpr double kShift = 3.0;
  RunLog wrapped = log;
  bool crossed = false;
  for (std::size_t k = 0; k < wrapped.samples.size(); ++k) {
    for (std::size_t i = 0; i < nominal.modules.size(); ++i) {
      double& steer = wrapped.samples[k].steer_rad[i];
      const double shifted = steer + kShift;
      log.samples[k].steer_rad[i] = shifted;
      steer = wrap_pi(shifted);
      if (k > 0 && std::abs(steer - wrapped.samples[k - 1].steer_rad[i]) > std::numbers::pi)
        crossed = true;
    }
  }
  ASSERT_TRUE(crossed) << "the test run never crosses +-pi";
  // The shifted twin needs the model's steering offsets shifted back.
  RobotModel shifted_nominal = nominal;
  for (SwpcModuleParams& m : shifted_nominal.modules) m.steering_offset_rad -= kShift;
  const GapResult plain = analyse_gap(shifted_nominal, to_run_data(log));
  const GapResult wrap = analyse_gap(shifted_nominal, to_run_data(wrapped));
  EXPECT_EQ(plain.sensor.verdict, wrap.sensor.verdict) << wrap.sensor.summary;
  EXPECT_EQ(plain.command.verdict, wrap.command.verdict) << wrap.command.summary;
  ASSERT_EQ(plain.sensor.named.size(), wrap.sensor.named.size());
  for (std::size_t e = 0; e < plain.sensor.named.size(); ++e) {
    EXPECT_EQ(plain.sensor.named[e].name, wrap.sensor.named[e].name);
    for (std::size_t i = 0; i < plain.sensor.named[e].values.size(); ++i)
      EXPECT_NEAR(plain.sensor.named[e].values[i], wrap.sensor.named[e].values[i], 1e-9);
  }
}

}  // namespace
}  // namespace swivel::model_gap

namespace swivel::model_gap {
namespace {

// Two circles of one June session driven clockwise and two anticlockwise: each calibrates a
// track on its own, the anticlockwise ones wider. Fitted against the radius each turned at,
// they show a right wheel smaller than the left, as the data's authors found with UMBmark on
// squares of other sessions (their sheet diff-UMBmark, session 230620202042: right 0.041977 m,
// left 0.042023 m, 0.11 %). Four runs fix it at about 3.5 sigma, past the calibration's 3, so
// the pooled model holds the track and the two radii.
TEST(RealRun, CirclesBothWaysRoundShowTheRightWheelSmallerThanTheLeft) {
  const RobotModel model = optiodom_model();
  const std::vector<RunData> runs = {
      import_vendored("250620202251_run-04"), import_vendored("250620202251_run-05"),
      import_vendored("250620202251_run-09"), import_vendored("250620202251_run-10")};
  const CrossRunResult cross = cross_validate(model, runs, {});
  ASSERT_EQ(cross.fits.size(), 4U);
  EXPECT_LT(cross.fits[0].turn_radius_m, -0.25);  // clockwise, radius about 0.32 m
  EXPECT_GT(cross.fits[3].turn_radius_m, 0.25);
  const TrackByTurn& t = cross.track_by_turn;
  ASSERT_TRUE(t.fitted);
  EXPECT_EQ(t.runs, 4U);
  // Right minus left, as a share of the radius: between 0.05 and 0.25 % smaller.
  EXPECT_LT(2.0 * t.radius_difference, -0.0005);
  EXPECT_GT(2.0 * t.radius_difference, -0.0025);
  EXPECT_LT(t.chi_square, 0.5 * t.chi_square_one_track);
  EXPECT_GT(std::abs(t.radius_difference), 3.0 * t.radius_difference_sigma);
  EXPECT_LT(std::abs(t.radius_difference), 5.0 * t.radius_difference_sigma);
  ASSERT_EQ(cross.pooled.effects.count("wheel_radius"), 1U);
  EXPECT_EQ(cross.pooled.effects.count("track_width"), 1U);
  const auto& radii = cross.pooled.effects.at("wheel_radius");
  EXPECT_LT(radii.at("right_scale"), radii.at("left_scale"));
}

}  // namespace
}  // namespace swivel::model_gap
