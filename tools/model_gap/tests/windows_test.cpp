// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/windows.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace swivel::model_gap {
namespace {

// A robot driving an arc at 100 Hz, motion capture on every other row (none from 20 to 25 s).
RunData arc_run(double noise_m, double noise_rad, unsigned seed) {
  RunData r;
  r.module_count = 2;
  r.wheel_rad.assign(2, {});
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int k = 0; k <= 4000; ++k) {
    const double t = 0.01 * k;
    r.t_s.push_back(t);
    r.cmd_vx_mps.push_back(0.3);
    r.cmd_vy_mps.push_back(0.0);
    r.cmd_wz_radps.push_back(0.2);
    r.wheel_rad[0].push_back(3.0 * t);
    r.wheel_rad[1].push_back(4.0 * t);
    r.gyro_radps.push_back(0.2);
    const double yaw = 0.2 * t;
    const bool sample = k % 2 == 0 && (t < 20.0 || t > 25.0);
    const double nan = std::nan("");
    r.truth_x_m.push_back(sample ? 1.5 * std::sin(yaw) + noise_m * gauss(rng) : nan);
    r.truth_y_m.push_back(sample ? 1.5 * (1.0 - std::cos(yaw)) + noise_m * gauss(rng) : nan);
    r.truth_yaw_rad.push_back(sample ? yaw + noise_rad * gauss(rng) : nan);
  }
  return r;
}

TEST(Windows, EndOnMotionCaptureAndSkipItsGaps) {
  const RunData run = arc_run(0.0, 0.0, 1);
  const auto windows = make_windows(run, 1.0, 0.0, 40.0);
  ASSERT_GT(windows.size(), 30U);
  for (std::size_t j = 0; j < windows.size(); ++j) {
    EXPECT_TRUE(std::isfinite(run.truth_x_m[windows[j].a]));
    EXPECT_TRUE(std::isfinite(run.truth_x_m[windows[j].b]));
    const double length = run.t_s[windows[j].b] - run.t_s[windows[j].a];
    EXPECT_GE(length, 1.0 - 1e-9);
    EXPECT_LE(length, 2.0);
    EXPECT_FALSE(run.t_s[windows[j].a] < 25.0 && run.t_s[windows[j].b] > 20.0) << "spans the gap";
    if (j > 0 && run.t_s[windows[j].a] < 20.0) {
      EXPECT_EQ(windows[j].a, windows[j - 1].b);
    }
  }
}

// The anchor reproduces the motion capture exactly on noise-free data, even when the shape
// it borrows is turned and shifted against the world (a drifted dead reckoning), and
// averages the noise down when there is some.
TEST(Windows, AnchorsAverageTheNoiseWithTheDeadReckonedShape) {
  const RunData clean = arc_run(0.0, 0.0, 1);
  std::vector<Pose2> shape;
  const double turn = 0.3;
  for (std::size_t k = 0; k < clean.size(); ++k) {
    const double yaw = 0.2 * clean.t_s[k];
    const double x = 1.5 * std::sin(yaw);
    const double y = 1.5 * (1.0 - std::cos(yaw));
    shape.push_back(Pose2{std::cos(turn) * x - std::sin(turn) * y + 2.0,
                          std::sin(turn) * x + std::cos(turn) * y - 1.0, yaw + turn});
  }
  const Pose2 exact = anchor(clean, shape, 1000, 5);
  EXPECT_NEAR(exact.x_m, clean.truth_x_m[1000], 1e-9);
  EXPECT_NEAR(exact.y_m, clean.truth_y_m[1000], 1e-9);
  EXPECT_NEAR(exact.yaw_rad, clean.truth_yaw_rad[1000], 1e-12);
  EXPECT_TRUE(std::isnan(anchor(clean, shape, 1001, 5).x_m));  // no motion capture on odd rows

  double raw = 0.0;
  double averaged = 0.0;
  int count = 0;
  for (unsigned seed = 1; seed <= 30; ++seed) {
    const RunData noisy = arc_run(0.001, 0.001, seed);
    for (std::size_t k = 200; k < 1800; k += 100) {
      const Pose2 a = anchor(noisy, shape, k, 5);
      raw += std::pow(noisy.truth_x_m[k] - clean.truth_x_m[k], 2);
      averaged += std::pow(a.x_m - clean.truth_x_m[k], 2);
      ++count;
    }
  }
  // Six samples within +-5 rows: about sqrt(6) less noise.
  EXPECT_LT(std::sqrt(averaged / count), 0.55 * std::sqrt(raw / count));
}

// How far the commands carry each caster's steering axis over a window at their slowest
// there, in caster offsets: the arc's 0.3 m/s and 0.2 rad/s move an axis at (0.2, 0.1) by
// (0.3 - 0.2 * 0.1, 0.2 * 0.2) = (0.28, 0.04) m/s; a row commanded to rest stops it.
TEST(Windows, TheSlowestRollOfEachCasterIsInItsOwnOffsets) {
  RunData run = arc_run(0.0, 0.0, 1);
  const auto windows = make_windows(run, 1.0, 0.0, 40.0);
  RobotModel model;
  EXPECT_TRUE(slowest_roll_offsets(run, windows, model).empty()) << "differential";
  model.drivetrain = DrivetrainKind::kSwpc;
  model.modules.resize(2);
  model.modules[0].x_m = 0.2;
  model.modules[0].y_m = 0.1;
  model.modules[0].caster_offset_m = 0.02;
  model.modules[1].caster_offset_m = 0.04;
  const std::size_t rest = windows[3].a + 10;
  run.cmd_vx_mps[rest] = 0.0;
  run.cmd_wz_radps[rest] = 0.0;
  const auto roll = slowest_roll_offsets(run, windows, model);
  ASSERT_EQ(roll.size(), 2U);
  ASSERT_EQ(roll[0].size(), windows.size());
  for (std::size_t j = 0; j < windows.size(); ++j) {
    const double length = run.t_s[windows[j].b] - run.t_s[windows[j].a];
    const double speed0 = j == 3 ? 0.0 : std::hypot(0.28, 0.04);
    const double speed1 = j == 3 ? 0.0 : 0.3;
    EXPECT_NEAR(roll[0][j], speed0 * length / 0.02, 1e-9) << j;
    EXPECT_NEAR(roll[1][j], speed1 * length / 0.04, 1e-9) << j;
  }
}

}  // namespace
}  // namespace swivel::model_gap
