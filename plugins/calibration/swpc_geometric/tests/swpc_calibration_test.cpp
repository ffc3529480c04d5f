// SPDX-License-Identifier: Apache-2.0
#include "swivel/calibration/swpc_calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "swivel/calibration/calibration_motion.hpp"
#include "test_robots.hpp"

namespace swivel::calibration {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

CalibrationInput make_input(const std::vector<SwpcModuleParams>& truth, std::mt19937_64& rng,
                            const CalibrationMotionOptions& opt = {}) {
  CalibrationInput input;
  std::string error;
  EXPECT_TRUE(generate_calibration_motion(truth, opt, rng, input, error)) << error;
  return input;
}

class NoiseFreeCalibration : public ::testing::TestWithParam<std::size_t> {};

// Tolerance: 1e-9 m and 1e-9 rad, about a million times the rounding error of the closed
// forms, and far below anything the data could resolve.
TEST_P(NoiseFreeCalibration, RecoversRandomTrueParameters) {
  const std::size_t n = GetParam();
  std::mt19937_64 rng(100 + n);
  for (int trial = 0; trial < 20; ++trial) {
    const auto truth = test::random_robot(n, rng);
    CalibrationMotionOptions opt;
    opt.start_pose = {0.5 * trial, -0.3, 0.4 * trial};
    const CalibrationResult res = calibrate(make_input(truth, rng, opt));
    ASSERT_TRUE(res.ok()) << res.reason();
    ASSERT_EQ(res.modules.size(), n);
    for (std::size_t m = 0; m < n; ++m) {
      const SwpcModuleParams& est = res.modules[m].params;
      EXPECT_NEAR(est.x_m, truth[m].x_m, 1e-9);
      EXPECT_NEAR(est.y_m, truth[m].y_m, 1e-9);
      EXPECT_NEAR(wrap_pi(est.steering_offset_rad - truth[m].steering_offset_rad), 0.0, 1e-9);
      EXPECT_NEAR(est.caster_offset_m, truth[m].caster_offset_m, 1e-9);
      EXPECT_NEAR(est.wheel_radius_m, truth[m].wheel_radius_m, 1e-9);
      EXPECT_EQ(res.modules[m].wheel_radius_estimates_m.size(), 2 * (n - 1));
    }
  }
}

TEST(NoiseFreeCalibrationDirection, ClockwiseRotationAndOtherLockedAnglesRecoverToo) {
  // docs/methods.md: the apex direction depends on the steering change, not on the turn direction.
  std::mt19937_64 rng(77);
  const auto truth = test::random_robot(4, rng);
  CalibrationMotionOptions opt;
  opt.rotation_rad = -1.2;
  opt.locked_angles_meas_rad = {170.0 * kDeg, -60.0 * kDeg};
  const CalibrationResult res = calibrate(make_input(truth, rng, opt));
  ASSERT_TRUE(res.ok()) << res.reason();
  for (std::size_t m = 0; m < truth.size(); ++m) {
    EXPECT_NEAR(res.modules[m].params.x_m, truth[m].x_m, 1e-9);
    EXPECT_NEAR(res.modules[m].params.y_m, truth[m].y_m, 1e-9);
    EXPECT_NEAR(res.modules[m].params.caster_offset_m, truth[m].caster_offset_m, 1e-9);
    EXPECT_NEAR(res.modules[m].params.wheel_radius_m, truth[m].wheel_radius_m, 1e-9);
    EXPECT_NEAR(wrap_pi(res.modules[m].params.steering_offset_rad - truth[m].steering_offset_rad),
                0.0, 1e-9);
  }
}

INSTANTIATE_TEST_SUITE_P(ModuleCounts, NoiseFreeCalibration, ::testing::Values(2, 3, 4, 6));

TEST(SteeringAxisFromPivots, ApexIsCounterClockwiseFromP1ToP2) {
  // Arrange: a module whose axis S, offset d and steering angles are known.
  const double sx = 0.2;
  const double sy = -0.1;
  const double d = 0.02;
  const double delta = 7.0 * kDeg;
  for (const double dphi_deg : {30.0, 120.0, 200.0, 330.0, -120.0}) {
    const double phi1m = 45.0 * kDeg;
    const double phi2m = phi1m + dphi_deg * kDeg;
    const double p1x = sx - d * std::cos(phi1m + delta);
    const double p1y = sy - d * std::sin(phi1m + delta);
    const double p2x = sx - d * std::cos(phi2m + delta);
    const double p2y = sy - d * std::sin(phi2m + delta);
    // Act
    const AxisGeometry g = steering_axis_from_pivots(p1x, p1y, p2x, p2y, phi1m, phi2m);
    // Assert
    EXPECT_NEAR(g.x_m, sx, 1e-15) << dphi_deg;
    EXPECT_NEAR(g.y_m, sy, 1e-15) << dphi_deg;
    EXPECT_NEAR(g.caster_offset_m, d, 1e-15) << dphi_deg;
    EXPECT_NEAR(g.steering_offset_rad, delta, 1e-14) << dphi_deg;
    // The clockwise apex (mirror image across P1P2) is a different point, d*2cos(..) away.
    const double dphi = std::fmod(dphi_deg * kDeg + 2.0 * std::numbers::pi, 2.0 * std::numbers::pi);
    const double a = -(std::numbers::pi - dphi) / 2.0;
    const double bx = (p2x - p1x) / (2.0 * std::sin(dphi / 2.0));
    const double by = (p2y - p1y) / (2.0 * std::sin(dphi / 2.0));
    const double cw_x = p1x + std::cos(a) * bx - std::sin(a) * by;
    const double cw_y = p1y + std::sin(a) * bx + std::cos(a) * by;
    EXPECT_GT(std::hypot(cw_x - sx, cw_y - sy), 1e-3) << dphi_deg;
  }
}

TEST(SteeringAxisFromPivots, RunOrderDoesNotMatter) {
  const double phi1m = 45.0 * kDeg;
  const double phi2m = 165.0 * kDeg;
  const double p1x = 0.3 - 0.02 * std::cos(phi1m);
  const double p1y = 0.1 - 0.02 * std::sin(phi1m);
  const double p2x = 0.3 - 0.02 * std::cos(phi2m);
  const double p2y = 0.1 - 0.02 * std::sin(phi2m);
  const AxisGeometry fwd = steering_axis_from_pivots(p1x, p1y, p2x, p2y, phi1m, phi2m);
  // The runs in the other order, on purpose.
  // NOLINTNEXTLINE(readability-suspicious-call-argument)
  const AxisGeometry rev = steering_axis_from_pivots(p2x, p2y, p1x, p1y, phi2m, phi1m);
  EXPECT_NEAR(fwd.x_m, rev.x_m, 1e-15);
  EXPECT_NEAR(fwd.y_m, rev.y_m, 1e-15);
  EXPECT_NEAR(fwd.caster_offset_m, rev.caster_offset_m, 1e-15);
  EXPECT_NEAR(fwd.steering_offset_rad, rev.steering_offset_rad, 1e-14);
}

TEST(FitPivot, RecoversCentreOfRotation) {
  const double px = 0.31;
  const double py = -0.12;
  std::vector<double> x;
  std::vector<double> y;
  std::vector<double> yaw;
  for (int k = 0; k < 50; ++k) {
    const double a = 3.0 + 0.02 * k;  // wraps through pi
    x.push_back(1.0 - (std::cos(a) * px - std::sin(a) * py));
    y.push_back(2.0 - (std::sin(a) * px + std::cos(a) * py));
    yaw.push_back(wrap_pi(a));
  }
  const PivotFit fit = fit_pivot(x, y, yaw);
  EXPECT_NEAR(fit.x_m, px, 1e-13);
  EXPECT_NEAR(fit.y_m, py, 1e-13);
  EXPECT_LT(fit.residual_rms_m, 1e-13);
  EXPECT_NEAR(fit.rotation_rad, 0.98, 1e-12);
}

struct NoiseStats {
  double mae_position_m = 0.0;
  double mae_r_m = 0.0;
  std::array<int, 5> covered{};  // x, y, delta, d, r
  int samples = 0;
};

NoiseStats run_noisy(double pos_noise_m, double yaw_noise_rad, int trials, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  NoiseStats st;
  for (int t = 0; t < trials; ++t) {
    const auto truth = test::random_robot(4, rng);
    CalibrationMotionOptions opt;
    opt.position_noise_m = pos_noise_m;
    opt.yaw_noise_rad = yaw_noise_rad;
    const CalibrationResult res = calibrate(make_input(truth, rng, opt));
    EXPECT_TRUE(res.ok()) << res.reason();
    if (!res.ok()) continue;
    for (std::size_t m = 0; m < truth.size(); ++m) {
      const auto& e = res.modules[m].params;
      const auto& s = res.modules[m].sigma;
      const double errs[5] = {e.x_m - truth[m].x_m, e.y_m - truth[m].y_m,
                              wrap_pi(e.steering_offset_rad - truth[m].steering_offset_rad),
                              e.caster_offset_m - truth[m].caster_offset_m,
                              e.wheel_radius_m - truth[m].wheel_radius_m};
      const double sig[5] = {s.x_m, s.y_m, s.steering_offset_rad, s.caster_offset_m,
                             s.wheel_radius_m};
      for (int i = 0; i < 5; ++i) st.covered[i] += std::abs(errs[i]) < 3.0 * sig[i] ? 1 : 0;
      st.mae_position_m += std::hypot(errs[0], errs[1]);
      st.mae_r_m += std::abs(errs[4]);
      ++st.samples;
    }
  }
  st.mae_position_m /= st.samples;
  st.mae_r_m /= st.samples;
  return st;
}

TEST(NoisyCalibration, ErrorsScaleWithNoise) {
  const NoiseStats low = run_noisy(0.1e-3, 0.05 * kDeg, 60, 7);
  const NoiseStats high = run_noisy(0.4e-3, 0.2 * kDeg, 60, 7);
  // Same seed, same robots, noise x4: first-order errors scale by 4 (sampling spread aside).
  EXPECT_GT(low.mae_position_m, 1e-6);
  EXPECT_NEAR(high.mae_position_m / low.mae_position_m, 4.0, 0.4);
  EXPECT_NEAR(high.mae_r_m / low.mae_r_m, 4.0, 0.4);
}

TEST(NoisyCalibration, ReportedSigmasCoverTrueErrors) {
  // 200 trials x 4 modules; a Gaussian error lies within 3 sigma 99.7 % of the time, so
  // 95 % leaves room for sigma estimates that are a little optimistic, not for wrong ones.
  const NoiseStats st = run_noisy(0.1e-3, 0.05 * kDeg, 200, 8);
  const char* names[5] = {"x", "y", "delta", "d", "r"};
  for (int i = 0; i < 5; ++i) {
    EXPECT_GE(static_cast<double>(st.covered[i]) / st.samples, 0.95) << names[i];
  }
}

class Degenerate : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937_64 rng(5);
    truth_ = test::random_robot(3, rng);
    input_ = make_input(truth_, rng);
    ASSERT_TRUE(calibrate(input_).ok());
  }
  void expect_refused(const std::string& check, const std::string& text) {
    const CalibrationResult res = calibrate(input_);
    EXPECT_FALSE(res.ok());
    EXPECT_TRUE(res.modules.empty());
    EXPECT_NE(res.reason().find(check), std::string::npos) << res.reason();
    EXPECT_NE(res.reason().find(text), std::string::npos) << res.reason();
  }
  std::vector<SwpcModuleParams> truth_;
  CalibrationInput input_;
};

TEST_F(Degenerate, TooLittleRotationRefused) {
  std::mt19937_64 rng(6);
  CalibrationMotionOptions opt;
  opt.rotation_rad = 10.0 * kDeg;
  input_ = make_input(truth_, rng, opt);
  expect_refused("enough_rotation", "turned only 9.74 deg (need 30.0)");  // last sample at 0.34 s
}

TEST_F(Degenerate, ModuleThatNeverMovedRefused) {
  auto& wheel = input_.runs[0].data.wheel_angle_rad[2];
  std::fill(wheel.begin(), wheel.end(), 1.0);
  expect_refused("modules_moved", "module 3's wheel turned 0.0000 rad while module 1 was locked");
}

TEST_F(Degenerate, NanSampleRefused) {
  input_.runs[3].data.yaw_rad[17] = std::numeric_limits<double>::quiet_NaN();
  expect_refused("finite_inputs", "run 4 (module 2 locked) holds a non-finite value");
}

TEST_F(Degenerate, EqualLockedAnglesRefused) {
  std::mt19937_64 rng(6);
  CalibrationMotionOptions opt;
  opt.locked_angles_meas_rad = {45.0 * kDeg, 45.0 * kDeg};
  input_ = make_input(truth_, rng, opt);
  expect_refused("locked_angles_distinct", "module 1 locked at 45.00 and 45.00 deg");
}

TEST_F(Degenerate, MissingRunRefused) {
  input_.runs.pop_back();
  expect_refused("input_structure", "module 3 has 1 locked runs, need exactly 2");
}

TEST_F(Degenerate, PivotThatDriftsRefused) {
  // The locked wheel slipping: the centre of rotation moves 5 cm during the run.
  auto& d = input_.runs[1].data;
  for (std::size_t k = 0; k < d.x_m.size(); ++k) {
    d.x_m[k] += 0.05 * static_cast<double>(k) / static_cast<double>(d.x_m.size());
  }
  expect_refused("pivot_fit", "did not turn about a fixed point");
}

TEST_F(Degenerate, InconsistentWheelRadiusRefused) {
  // One run's encoder reads 10 % more (e.g. that wheel slipped): r estimates disagree.
  for (double& v : input_.runs[2].data.wheel_angle_rad[0]) v *= 1.1;
  expect_refused("wheel_radius_consistency", "module 1's 4 r estimates");
}

TEST_F(Degenerate, VerdictListsEveryCheckWhenAccepted) {
  const CalibrationResult res = calibrate(input_);
  ASSERT_TRUE(res.ok());
  const std::string text = res.verdict.text();
  for (const char* check : {"enough_rotation", "pivot_fit", "modules_moved", "lock_held",
                            "locked_angles_distinct", "geometry", "wheel_radius_consistency"}) {
    EXPECT_NE(text.find(std::string("PASS ") + check), std::string::npos) << text;
  }
  EXPECT_EQ(res.reason(), "");
}

}  // namespace
}  // namespace swivel::calibration
