// SPDX-License-Identifier: Apache-2.0
// The statistics of a Table 5 study on made-up runs whose figures can be worked out by hand.

#include "square_summary.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "swivel/calibration/monte_carlo.hpp"

namespace swivel::lab {
namespace {

RobotModel table4() {
  RobotModel m;
  m.drivetrain = DrivetrainKind::kSwpc;
  m.modules = calibration::paper_table4_modules();
  return m;
}

// Runs with these position errors, clockwise first; heading errors are ten times them.
TrackedModel tracked(const RobotModel& model, const std::vector<double>& cw,
                     const std::vector<double>& ccw) {
  TrackedModel t;
  t.model = model;
  for (const bool counter_clockwise : {false, true}) {
    const std::vector<double>& errors = counter_clockwise ? ccw : cw;
    for (std::size_t i = 0; i < errors.size(); ++i) {
      TrackedRun r;
      r.counter_clockwise = counter_clockwise;
      r.index = static_cast<int>(i);
      r.position_error_m = errors[i];
      r.heading_error_deg = 10.0 * errors[i];
      t.runs.push_back(r);
    }
  }
  return t;
}

TEST(SquareSummaryTest, DirectionsAreStrataOfEqualWeight) {
  // CW mean 0.2 (se 0.1), CCW mean 0.6 (se 0): overall 0.4 with se sqrt(0.1^2 + 0) / 2.
  const EndPoseError e = end_pose_error(tracked(table4(), {0.1, 0.3}, {0.6, 0.6}));
  EXPECT_DOUBLE_EQ(e.position_m.value, 0.4);
  EXPECT_NEAR(e.position_m.standard_error, 0.05, 1e-15);
  EXPECT_DOUBLE_EQ(e.heading_deg.value, 4.0);
}

TEST(SquareSummaryTest, ChangesSpreadAndAccuracyOverCalibratedModels) {
  const RobotModel truth = table4();
  SquareStudy study;
  study.nominal = tracked(truth, {1.0, 1.0}, {1.0, 1.0});
  study.exact = tracked(truth, {0.2, 0.2}, {0.2, 0.2});
  // Three calibrated models: 0.3, 0.5 and 1.3 (worse than the design values' 1.0). The
  // first is off by 0.1 deg in every steering offset and 0.3 mm in module 1's x.
  CalibratedModel a;
  a.tracked = tracked(truth, {0.3, 0.3}, {0.3, 0.3});
  for (SwpcModuleParams& m : a.tracked.model.modules) {
    m.steering_offset_rad += 0.1 * std::numbers::pi / 180.0;
  }
  a.tracked.model.modules[0].x_m += 0.3e-3;
  CalibratedModel b;
  b.tracked = tracked(truth, {0.5, 0.5}, {0.5, 0.5});
  CalibratedModel c;
  c.tracked = tracked(truth, {1.3, 1.3}, {1.3, 1.3});
  study.calibrated = {a, b, c};

  const SquareSummary s = summarize_square(study, truth);

  EXPECT_NEAR(s.exact_position_change.value, -0.8, 1e-12);
  EXPECT_NEAR(s.calibrated.position_m.value, 0.7, 1e-12);
  // Over models: sample std of 0.3, 0.5, 1.3 is sqrt(0.28), over sqrt(3).
  EXPECT_NEAR(s.calibrated.position_m.standard_error, std::sqrt(0.28 / 3.0), 1e-12);
  EXPECT_NEAR(s.position_change.value, -0.3, 1e-12);
  ASSERT_EQ(s.seed_position_change.size(), 3U);
  EXPECT_NEAR(s.position_spread.min, -0.7, 1e-12);
  EXPECT_NEAR(s.position_spread.median, -0.5, 1e-12);
  EXPECT_NEAR(s.position_spread.max, 0.3, 1e-12);
  EXPECT_EQ(s.position_worse, 1U);
  EXPECT_EQ(s.heading_worse, 1U);
  // rms over three models of which one is off: the error over sqrt(3).
  ASSERT_EQ(s.accuracy.size(), 4U);
  EXPECT_NEAR(s.accuracy[0].position_mm, 0.3 / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(s.accuracy[1].position_mm, 0.0, 1e-12);
  for (const ModuleAccuracy& m : s.accuracy) {
    EXPECT_NEAR(m.steering_offset_deg, 0.1 / std::sqrt(3.0), 1e-9);
    EXPECT_NEAR(m.wheel_radius_mm, 0.0, 1e-12);
  }
}

TEST(SquareSummaryTest, OneGivenModelTakesTheStandardErrorOfItsRuns) {
  const RobotModel truth = table4();
  SquareStudy study;
  study.nominal = tracked(truth, {1.0, 1.0}, {1.0, 1.0});
  study.exact = tracked(truth, {0.2, 0.2}, {0.2, 0.2});
  CalibratedModel given;
  given.tracked = tracked(truth, {0.1, 0.3}, {0.6, 0.6});
  study.calibrated = {given};
  const SquareSummary s = summarize_square(study, truth);
  EXPECT_DOUBLE_EQ(s.calibrated.position_m.value, 0.4);
  EXPECT_NEAR(s.calibrated.position_m.standard_error, 0.05, 1e-15);
}

}  // namespace
}  // namespace swivel::lab
