// SPDX-License-Identifier: Apache-2.0
// ReadingGap: the odometry's model while the hardware gives no readings.

#include "swivel/rt/reading_gap.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace swivel::rt {
namespace {

constexpr double kDtS = 0.001;

PoseEstimate start_estimate() {
  PoseEstimate e;
  e.pose = {1.0, 2.0, 0.0};
  e.has_covariance = true;
  e.covariance = {1e-4, 0.0, 0.0, 0.0, 1e-4, 0.0, 0.0, 0.0, 1e-5};
  return e;
}

constexpr std::array<double, 9> kTwistCovariance{4e-8, 0.0, 0.0, 0.0, 1e-8, 0.0, 0.0, 0.0, 9e-8};

// Brakes from 0.3 m/s at 1 m/s^2 over `cycles`, as the controlled stop does.
void brake(ReadingGap& gap, double& t_s, int cycles) {
  for (int i = 0; i < cycles; ++i) {
    t_s += kDtS;
    gap.advance(Twist2{std::max(0.3 - 1.0 * (t_s - 10.0), 0.0), 0.0, 0.0}, t_s);
  }
}

TEST(ReadingGap, TwistIsTheModelAndItsVarianceCoversTheSpeedLastMeasured) {
  ReadingGap gap;
  gap.begin(start_estimate(), Twist2{0.3, 0.0, 0.0}, &kTwistCovariance, 10.0);
  ASSERT_TRUE(gap.active());
  ASSERT_TRUE(gap.has_twist());
  EXPECT_DOUBLE_EQ(gap.twist_covariance()[0], 4e-8);  // nothing modelled yet
  double t_s = 10.0;
  brake(gap, t_s, 100);
  EXPECT_NEAR(gap.twist().vx_mps, 0.2, 1e-9);
  // sigma: the last measured one plus the distance to the speed last measured.
  EXPECT_NEAR(std::sqrt(gap.twist_covariance()[0]), 2e-4 + 0.1, 1e-9);
  EXPECT_NEAR(std::sqrt(gap.twist_covariance()[4]), 1e-4, 1e-12);
  EXPECT_NEAR(std::sqrt(gap.twist_covariance()[8]), 3e-4, 1e-12);
  EXPECT_EQ(gap.twist_covariance()[1], 0.0);
}

TEST(ReadingGap, PoseIsDeadReckonedAndItsCovarianceGrows) {
  ReadingGap gap;
  gap.begin(start_estimate(), Twist2{0.3, 0.0, 0.0}, &kTwistCovariance, 10.0);
  double t_s = 10.0;
  double previous_variance = start_estimate().covariance[0];
  for (int k = 0; k < 5; ++k) {
    brake(gap, t_s, 100);
    EXPECT_GT(gap.estimate().covariance[0], previous_variance);
    EXPECT_DOUBLE_EQ(gap.estimate().covariance[4] - start_estimate().covariance[4],
                     gap.estimate().covariance[0] - start_estimate().covariance[0]);
    previous_variance = gap.estimate().covariance[0];
  }
  // 0.3 m/s braked at 1 m/s^2: 0.045 m, straight ahead.
  EXPECT_NEAR(gap.estimate().pose.x_m - 1.0, 0.045, 1e-3);
  EXPECT_NEAR(gap.estimate().pose.y_m, 2.0, 1e-12);
  // The position's sigma grew by the integral of the speed's: at least the distance the robot
  // would have covered had it kept its speed minus the braking distance (0.15 - 0.045 m).
  EXPECT_GT(std::sqrt(gap.estimate().covariance[0] - 1e-4), 0.1);
}

TEST(ReadingGap, ResumeKeepsThePoseAndWidensTheCovarianceByTheMeasuredDifference) {
  ReadingGap gap;
  gap.begin(start_estimate(), Twist2{0.3, 0.0, 0.0}, &kTwistCovariance, 10.0);
  double t_s = 10.0;
  brake(gap, t_s, 499);
  const PoseEstimate reckoned = gap.estimate();
  OdometryIncrement measured;
  measured.valid = true;
  measured.dt_s = 0.5;
  measured.delta = {reckoned.pose.x_m - 1.0 + 0.003, 0.004, 0.002};  // 5 mm and 2 mrad off
  const PoseEstimate handed = gap.resume(measured, t_s);
  EXPECT_FALSE(gap.active());
  EXPECT_TRUE(gap.has_twist());  // until the twist is measured again
  EXPECT_DOUBLE_EQ(handed.pose.x_m, reckoned.pose.x_m);
  EXPECT_DOUBLE_EQ(handed.pose.y_m, reckoned.pose.y_m);
  EXPECT_NEAR(gap.last_position_error_m(), 0.005, 1e-12);
  EXPECT_NEAR(gap.last_heading_error_rad(), 0.002, 1e-12);
  EXPECT_NEAR(handed.covariance[0], reckoned.covariance[0] + 0.005 * 0.005, 1e-15);
  EXPECT_NEAR(handed.covariance[4], reckoned.covariance[4] + 0.005 * 0.005, 1e-15);
  EXPECT_NEAR(handed.covariance[8], reckoned.covariance[8] + 0.002 * 0.002, 1e-15);
  gap.forget_twist();
  EXPECT_FALSE(gap.has_twist());
}

TEST(ReadingGap, WithoutAMeasurementTheDeadReckonedEstimateIsHandedOver) {
  ReadingGap gap;
  gap.begin(start_estimate(), Twist2{0.3, 0.0, 0.0}, &kTwistCovariance, 10.0);
  double t_s = 10.0;
  brake(gap, t_s, 10);
  const PoseEstimate reckoned = gap.estimate();
  const PoseEstimate handed = gap.resume(OdometryIncrement{}, t_s);
  EXPECT_EQ(handed.covariance, reckoned.covariance);
  EXPECT_DOUBLE_EQ(handed.pose.x_m, reckoned.pose.x_m);
}

TEST(ReadingGap, NoCovarianceIsInventedWhereThereWasNone) {
  ReadingGap gap;
  PoseEstimate start;
  start.pose = {0.0, 0.0, 0.5};
  gap.begin(start, Twist2{0.2, 0.0, 0.1}, nullptr, 0.0);
  gap.advance(Twist2{0.1, 0.0, 0.05}, 0.1);
  EXPECT_FALSE(gap.estimate().has_covariance);
  EXPECT_FALSE(gap.has_twist_covariance());
  // Dead reckoning on an arc: the heading moved by the turn rate held.
  EXPECT_NEAR(gap.estimate().pose.yaw_rad, 0.5 + 0.1 * 0.1, 1e-12);
}

}  // namespace
}  // namespace swivel::rt
