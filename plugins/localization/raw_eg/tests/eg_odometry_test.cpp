// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/eg_odometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace swivel::localization {
namespace {

constexpr double kDt = 0.001;

// Exact motion over one step at constant (v, w), in the start frame.
Pose2 arc_increment(double v_mps, double w_radps, double dt_s) {
  const double a = w_radps * dt_s;
  if (a == 0.0) return Pose2{v_mps * dt_s, 0.0, 0.0};
  return Pose2{v_mps / w_radps * std::sin(a), v_mps / w_radps * (1.0 - std::cos(a)), a};
}

void expect_on_circle(const EgOdometry& eg, double v, double w, double t, double tol_m) {
  const double r = v / w;
  EXPECT_NEAR(eg.pose().x_m, r * std::sin(w * t), tol_m);
  EXPECT_NEAR(eg.pose().y_m, r * (1.0 - std::cos(w * t)), tol_m);
  EXPECT_NEAR(eg.unwrapped_yaw_rad(), w * t, 1e-9);
}

TEST(EgOdometry, EncoderHeadingFollowsExactCircle) {
  EgOdometry eg(EgConfig{HeadingSource::kEncoders, 1.0, 0.0});
  const double v = 0.3;
  const double w = 0.5;
  const int steps = 20000;  // 20 s: more than a full turn
  for (int i = 0; i < steps; ++i) ASSERT_TRUE(eg.step(arc_increment(v, w, kDt), kDt, 0.0, false));
  expect_on_circle(eg, v, w, steps * kDt, 1e-9);
  EXPECT_NEAR(eg.distance_m(), 2.0 * v / w * std::sin(0.5 * w * kDt) * steps, 1e-9);
}

TEST(EgOdometry, GyroHeadingFollowsExactCircle) {
  EgOdometry eg(EgConfig{HeadingSource::kGyro, 1.0, 0.0});
  const double v = 0.3;
  const double w = -0.8;
  const int steps = 20000;
  for (int i = 0; i < steps; ++i) ASSERT_TRUE(eg.step(arc_increment(v, w, kDt), kDt, w, true));
  EXPECT_TRUE(eg.last_step_used_gyro());
  expect_on_circle(eg, v, w, steps * kDt, 1e-9);
}

TEST(EgOdometry, GyroBiasDriftsHeadingByBiasTimesTime) {
  // Straight odometry, gyro reading only its bias: the heading drifts by bias * t and the
  // position bends onto the circle of radius v / bias.
  EgOdometry eg(EgConfig{HeadingSource::kGyro, 1.0, 0.0});
  const double v = 0.3;
  const double bias = 0.01;
  const int steps = 30000;
  for (int i = 0; i < steps; ++i) ASSERT_TRUE(eg.step(arc_increment(v, 0.0, kDt), kDt, bias, true));
  const double t = steps * kDt;
  EXPECT_NEAR(eg.unwrapped_yaw_rad(), bias * t, 1e-12);
  // Chord (d) instead of 2 R sin(a/2) per step: relative error a^2/24 = 4e-18, negligible.
  EXPECT_NEAR(eg.pose().x_m, v / bias * std::sin(bias * t), 1e-9);
  EXPECT_NEAR(eg.pose().y_m, v / bias * (1.0 - std::cos(bias * t)), 1e-9);
}

TEST(EgOdometry, KnownGyroBiasAndScaleAreCorrected) {
  EgOdometry eg(EgConfig{HeadingSource::kGyro, 1.05, 0.01});
  const double w = 0.4;
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(eg.step(arc_increment(0.2, w, kDt), kDt, 1.05 * w + 0.01, true));
  }
  EXPECT_NEAR(eg.unwrapped_yaw_rad(), w * 1.0, 1e-12);
}

TEST(EgOdometry, InvalidGyroFallsBackToOdometryHeading) {
  EgOdometry eg(EgConfig{HeadingSource::kGyro, 1.0, 0.0});
  ASSERT_TRUE(eg.step(arc_increment(0.3, 0.5, kDt), kDt, 99.0, false));
  EXPECT_FALSE(eg.last_step_used_gyro());
  EXPECT_NEAR(eg.unwrapped_yaw_rad(), 0.5 * kDt, 1e-15);
}

TEST(EgOdometry, HolonomicIncrementMovesSideways) {
  // Facing +y, a pure left step in the robot frame moves the robot towards -x.
  EgOdometry eg(EgConfig{HeadingSource::kEncoders, 1.0, 0.0});
  eg.reset(Pose2{1.0, 2.0, std::numbers::pi / 2.0});
  ASSERT_TRUE(eg.step(Pose2{0.0, 0.01, 0.0}, kDt, 0.0, false));
  EXPECT_NEAR(eg.pose().x_m, 0.99, 1e-15);
  EXPECT_NEAR(eg.pose().y_m, 2.0, 1e-15);
}

TEST(EgOdometry, NonFiniteInputLeavesStateUnchanged) {
  EgOdometry eg;
  eg.reset(Pose2{1.0, 2.0, 0.5});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(eg.step(Pose2{nan, 0.0, 0.0}, kDt, 0.0, true));
  EXPECT_FALSE(eg.step(Pose2{0.01, 0.0, 0.0}, kDt, nan, true));
  EXPECT_EQ(eg.pose().x_m, 1.0);
  EXPECT_EQ(eg.pose().yaw_rad, 0.5);
}

}  // namespace
}  // namespace swivel::localization
