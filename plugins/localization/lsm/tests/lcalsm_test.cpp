// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/lcalsm.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <type_traits>

#include "swivel/localization/eg_odometry.hpp"

namespace swivel::localization {
namespace {

LsmConfig every_sample(LsmMode mode = LsmMode::kPaper) {
  LsmConfig c;
  c.mode = mode;
  c.sample_distance_m = 0.0;
  c.sample_period_s = 0.0;
  return c;
}

TEST(FitLine, MatchesCramersRuleByHand) {
  // x = 0..3, y = 1, 3, 5, 8: n = 4, Sx = 6, Sxx = 14, Sy = 17, Sxy = 37, det = 20,
  // a = (4*37 - 6*17)/20 = 2.3, b = (14*17 - 6*37)/20 = 0.8.
  const Point2 pts[] = {{0, 1}, {1, 3}, {2, 5}, {3, 8}};
  const LineFit fit = fit_line(pts, 4, false);
  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.a, 2.3, 1e-14);
  EXPECT_NEAR(fit.b, 0.8, 1e-14);
}

TEST(FitLine, RecoversKnownLineExactlyFarFromOrigin) {
  Point2 pts[10];
  for (int j = 0; j < 10; ++j) {
    const double x = 1000.0 + 0.02 * j;
    pts[j] = Point2{x, -0.3 * x + 7.0};
  }
  const LineFit fit = fit_line(pts, 10, false);
  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.a, -0.3, 1e-9);
  EXPECT_NEAR(fit.a * 1000.1 + fit.b, -0.3 * 1000.1 + 7.0, 1e-10);
}

TEST(FitLine, VerticalLineNeedsTheSwappedForm) {
  const Point2 pts[] = {{2, 0}, {2, 0.5}, {2, 1}, {2, 1.5}};
  EXPECT_FALSE(fit_line(pts, 4, false).ok);  // singular normal equations
  const LineFit fit = fit_line(pts, 4, true);
  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.a, 0.0, 1e-15);
  EXPECT_NEAR(fit.b, 2.0, 1e-15);
}

// Drives along `heading` from `start` with white position noise (not drift): the case the
// paper's method is built for. Returns (rms raw error, rms output error) across the track.
std::pair<double, double> noisy_line_errors(double heading, LsmMode mode) {
  Lcalsm lsm;
  lsm.configure(every_sample(mode));
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.01);
  const double c = std::cos(heading);
  const double s = std::sin(heading);
  double raw_sq = 0.0;
  double out_sq = 0.0;
  int n = 0;
  for (int j = 0; j < 400; ++j) {
    const double along = 0.02 * j;
    const double tx = 1.0 + along * c;
    const double ty = 3.0 + along * s;
    const Pose2 eg{tx + noise(rng), ty + noise(rng), heading};
    lsm.push(eg, heading, along, 0.0);
    const Pose2 out = lsm.output(eg);
    if (j >= 20) {
      // Lateral error only: along-track noise is not what a line fit addresses.
      raw_sq += std::pow(-(eg.x_m - tx) * s + (eg.y_m - ty) * c, 2);
      out_sq += std::pow(-(out.x_m - tx) * s + (out.y_m - ty) * c, 2);
      ++n;
    }
  }
  return {std::sqrt(raw_sq / n), std::sqrt(out_sq / n)};
}

TEST(Lcalsm, ReducesWhiteNoiseOnStraightLine) {
  const auto [raw, out] = noisy_line_errors(0.0, LsmMode::kPaper);
  EXPECT_NEAR(raw, 0.01, 0.0015);
  EXPECT_LT(out, 0.7 * raw);
}

TEST(Lcalsm, HandlesVerticalLine) {
  const auto [raw, out] = noisy_line_errors(std::numbers::pi / 2.0, LsmMode::kPaper);
  EXPECT_LT(out, 0.7 * raw);
  const auto [raw_steep, out_steep] = noisy_line_errors(1.4, LsmMode::kPaper);
  EXPECT_LT(out_steep, 0.7 * raw_steep);
}

TEST(Lcalsm, ReplacesWindowByFittedValues) {
  Lcalsm lsm;
  LsmConfig c = every_sample();
  c.window_points = 4;
  lsm.configure(c);
  // x = 0..3, y = 1, 1.3, 1.5, 1.8: Sy = 5.6, Sxy = 9.7, a = (4*9.7 - 6*5.6)/20 = 0.26,
  // b = (14*5.6 - 6*9.7)/20 = 1.01.
  const Point2 pts[] = {{0, 1}, {1, 1.3}, {2, 1.5}, {3, 1.8}};
  for (const Point2& p : pts) lsm.push(Pose2{p.x_m, p.y_m, 0.0}, 0.0, p.x_m, 0.0);
  // Replaced by the fitted values; x kept.
  for (std::size_t age = 0; age < 4; ++age) {
    const Point2 p = lsm.point(age);
    EXPECT_NEAR(p.y_m, 0.26 * p.x_m + 1.01, 1e-13) << age;
  }
  EXPECT_NEAR(lsm.correction().y_m, 0.26 * 3.0 + 1.01 - 1.8, 1e-13);
  EXPECT_EQ(lsm.correction().x_m, 0.0);
}

TEST(Lcalsm, FallsBackToEgOnTurns) {
  Lcalsm lsm;
  lsm.configure(every_sample());
  // A turn in place-ish: 0.05 rad per sample, 0.45 rad across a 10-point window.
  for (int j = 0; j < 30; ++j) {
    const double yaw = 0.05 * j;
    const Pose2 eg{0.3 * std::sin(yaw), 0.3 * (1.0 - std::cos(yaw)), yaw};
    lsm.push(eg, yaw, 0.015 * j, 0.0);
    if (j >= 3) {  // from 3 samples on, the window spans more than 0.1 rad
      EXPECT_TRUE(lsm.in_turn()) << j;
      const Pose2 out = lsm.output(eg);
      EXPECT_EQ(out.x_m, eg.x_m);
      EXPECT_EQ(out.y_m, eg.y_m);
    }
  }
}

TEST(Lcalsm, HeadingAlignedFollowsAGentleCurve) {
  // An arc of radius 3 m sampled every 0.02 m turns 0.06 rad across a 10-point window: no
  // window shows a turn, yet the path leaves the line it set out on. Flattening it onto that
  // line would be off by the arc's sagitta (0.13 m after 0.9 m); a new segment starts once the
  // heading has left the segment's by 0.1 rad, so the output stays within the sagitta of a
  // 0.1 rad arc (3 m x (1 - cos 0.1) = 15 mm).
  Lcalsm lsm;
  lsm.configure(every_sample(LsmMode::kHeadingAligned));
  constexpr double kRadiusM = 3.0;
  double max_error_m = 0.0;
  for (int j = 0; j <= 150; ++j) {
    const double along_m = 0.02 * j;
    const double yaw = along_m / kRadiusM;
    const Pose2 eg{kRadiusM * std::sin(yaw), kRadiusM * (1.0 - std::cos(yaw)), yaw};
    lsm.push(eg, yaw, along_m, 0.0);
    EXPECT_FALSE(lsm.in_turn()) << j;
    const Pose2 out = lsm.output(eg);
    max_error_m = std::max(max_error_m, std::hypot(out.x_m - eg.x_m, out.y_m - eg.y_m));
  }
  EXPECT_LT(max_error_m, 0.016);
}

TEST(Lcalsm, StorageIsFixedAndDecimatedByDistance) {
  static_assert(std::is_trivially_copyable_v<Lcalsm>);
  Lcalsm lsm;
  LsmConfig c;  // defaults: k = 10, one sample per 0.02 m
  lsm.configure(c);
  for (int i = 0; i <= 10000; ++i) {
    const double x = 0.0003 * i;  // 0.3 m/s at 1 kHz, 3 m in all
    lsm.push(Pose2{x, 0.0, 0.0}, 0.0, x, 0.001 * i);
  }
  EXPECT_EQ(lsm.size(), 10U);
  EXPECT_NEAR(static_cast<double>(lsm.stored()), 3.0 / 0.02 + 1.0, 1.0);
}

TEST(Lcalsm, DecimatesByPeriodWhenAsked) {
  Lcalsm lsm;
  LsmConfig c;
  c.sample_distance_m = 0.0;
  c.sample_period_s = 0.05;
  lsm.configure(c);
  for (int i = 0; i <= 1000; ++i) lsm.push(Pose2{0.0003 * i, 0.0, 0.0}, 0.0, 0.0003 * i, 0.001 * i);
  EXPECT_NEAR(static_cast<double>(lsm.stored()), 21.0, 1.0);
}

// The finding. A realistic straight E/G run: true path (0,3) -> (8,3) at 0.3 m/s, wheels
// quantized to 4096 counts/rev, gyro with a small residual bias (5e-4 rad/s) and white noise
// (0.002 rad/s per 1 kHz sample). The E/G error is drift, not noise; a 10-point fit over
// 0.2 m cannot tell drift from motion, so the faithful method changes the error by almost
// nothing, while heading_aligned removes the lateral drift.
double max_error_on_drifting_run(LsmMode mode, bool compensate) {
  const double dt = 0.001;
  const double v = 0.3;
  const double r = 0.075;
  const double counts = 4096.0;
  const double rad_per_count = 2.0 * std::numbers::pi / counts;
  EgOdometry eg(EgConfig{HeadingSource::kGyro, 1.0, 0.0});
  eg.reset(Pose2{0.0, 3.0, 0.0});
  Lcalsm lsm;
  LsmConfig c;
  c.mode = mode;
  lsm.configure(c);
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> gyro_noise(0.0, 0.002);
  double prev_counts = 0.0;
  double max_err = 0.0;
  const int steps = static_cast<int>(8.0 / v / dt);
  for (int i = 1; i <= steps; ++i) {
    const double t = i * dt;
    const double wheel_counts = std::floor(v * t / r / rad_per_count);
    const double d = (wheel_counts - prev_counts) * rad_per_count * r;
    prev_counts = wheel_counts;
    eg.step(Pose2{d, 0.0, 0.0}, dt, 5e-4 + gyro_noise(rng), true);
    lsm.push(eg.pose(), eg.unwrapped_yaw_rad(), eg.distance_m(), t);
    const Pose2 out = compensate ? lsm.output(eg.pose()) : eg.pose();
    max_err = std::max(max_err, std::hypot(out.x_m - v * t, out.y_m - 3.0));
  }
  return max_err;
}

TEST(Lcalsm, FaithfulMethodCannotRemoveDriftButHeadingAlignedCan) {
  const double raw = max_error_on_drifting_run(LsmMode::kPaper, false);
  const double paper = max_error_on_drifting_run(LsmMode::kPaper, true);
  const double aligned = max_error_on_drifting_run(LsmMode::kHeadingAligned, true);
  std::printf(
      "max error on a drifting 8 m run: E/G %.4f m, paper %.4f m (%+.1f %%), "
      "heading_aligned %.4f m (%+.1f %%)\n",
      raw, paper, 100.0 * (paper - raw) / raw, aligned, 100.0 * (aligned - raw) / raw);
  EXPECT_GT(raw, 0.01);  // the drift is real: about bias v t^2 / 2 = 5 cm
  EXPECT_LT(std::abs(paper - raw), 0.1 * raw);
  EXPECT_LT(aligned, 0.5 * raw);
}

}  // namespace
}  // namespace swivel::localization
