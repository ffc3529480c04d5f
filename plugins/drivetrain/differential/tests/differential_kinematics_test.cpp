// SPDX-License-Identifier: Apache-2.0
#include "swivel/differential/differential_kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace swivel::differential {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr DifferentialParams kDocent{0.075, 0.075, 0.40};
constexpr DifferentialParams kUneven{0.070, 0.080, 0.40};

TEST(DifferentialKinematics, StraightLineDrivesBothWheelsAlike) {
  const WheelRates rates = inverse(kDocent, 0.3, 0.0);
  EXPECT_NEAR(rates.left_radps, 4.0, 1e-12);  // 0.3 / 0.075
  EXPECT_NEAR(rates.right_radps, 4.0, 1e-12);
}

TEST(DifferentialKinematics, SpinInPlaceDrivesWheelsOpposite) {
  const WheelRates rates = inverse(kDocent, 0.0, 1.0);
  EXPECT_NEAR(rates.left_radps, -0.2 / 0.075, 1e-12);
  EXPECT_NEAR(rates.right_radps, 0.2 / 0.075, 1e-12);
}

TEST(DifferentialKinematics, ArcMatchesHandComputedRates) {
  // vx = 0.3, wz = 0.5: wheel speeds 0.3 -+ 0.5 * 0.2 = 0.2 and 0.4 m/s.
  const WheelRates rates = inverse(kUneven, 0.3, 0.5);
  EXPECT_NEAR(rates.left_radps, 0.2 / 0.070, 1e-12);
  EXPECT_NEAR(rates.right_radps, 0.4 / 0.080, 1e-12);
}

TEST(DifferentialKinematics, ForwardInvertsInverse) {
  const Twist2 t = forward(kUneven, inverse(kUneven, -0.17, 0.83));
  EXPECT_NEAR(t.vx_mps, -0.17, 1e-12);
  EXPECT_EQ(t.vy_mps, 0.0);
  EXPECT_NEAR(t.wz_radps, 0.83, 1e-12);
}

TEST(DifferentialKinematics, IncrementOnQuarterCircleIsExact) {
  // Radius 1 m, a quarter turn: each wheel travels (1 -+ b/2) * pi/2; the robot ends at
  // (1, 1) in the start frame, facing +y.
  const double dyaw = kPi / 2.0;
  const double dpsi_left = (1.0 - 0.2) * dyaw / kUneven.wheel_radius_left_m;
  const double dpsi_right = (1.0 + 0.2) * dyaw / kUneven.wheel_radius_right_m;
  const Pose2 delta = forward_increment(kUneven, dpsi_left, dpsi_right);
  EXPECT_NEAR(delta.x_m, 1.0, 1e-12);
  EXPECT_NEAR(delta.y_m, 1.0, 1e-12);
  EXPECT_NEAR(delta.yaw_rad, dyaw, 1e-12);
}

TEST(DifferentialKinematics, IncrementsComposeToTheSameArc) {
  // 1000 small increments composed must land where one large increment does.
  const double dpsi_left = 3.0;
  const double dpsi_right = 5.0;
  const Pose2 whole = forward_increment(kDocent, dpsi_left, dpsi_right);
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
  const int steps = 1000;
  for (int i = 0; i < steps; ++i) {
    const Pose2 d = forward_increment(kDocent, dpsi_left / steps, dpsi_right / steps);
    x += std::cos(yaw) * d.x_m - std::sin(yaw) * d.y_m;
    y += std::sin(yaw) * d.x_m + std::cos(yaw) * d.y_m;
    yaw += d.yaw_rad;
  }
  EXPECT_NEAR(x, whole.x_m, 1e-12);
  EXPECT_NEAR(y, whole.y_m, 1e-12);
  EXPECT_NEAR(yaw, whole.yaw_rad, 1e-12);
}

TEST(DifferentialKinematics, TinyTurnsKeepFullPrecision) {
  // Long-double reference; (1 - cos a) computed naively would lose half its digits here.
  for (const double dyaw : {0.0, 1e-12, 1e-8, 1e-4, 0.3}) {
    const double d = 0.01;
    const double dpsi_left = (d - dyaw * 0.2) / 0.075;
    const double dpsi_right = (d + dyaw * 0.2) / 0.075;
    const Pose2 delta = forward_increment(kDocent, dpsi_left, dpsi_right);
    // Reference at the angle the wheels actually encode (rounding moves it by ~1e-18).
    ASSERT_NEAR(delta.yaw_rad, dyaw, 1e-15);
    const long double a = delta.yaw_rad;
    const long double s = std::sin(a / 2.0L);
    const long double x_ref = a == 0.0L ? d : d * std::sin(a) / a;
    const long double y_ref = a == 0.0L ? 0.0L : d * 2.0L * s * s / a;
    EXPECT_NEAR(delta.x_m, static_cast<double>(x_ref), 1e-17) << dyaw;
    EXPECT_NEAR(delta.y_m, static_cast<double>(y_ref), 1e-14 * std::abs(static_cast<double>(y_ref)))
        << dyaw;
  }
}

TEST(DifferentialKinematics, LimitScaleKeepsFastestWheelAtLimit) {
  // vx = 2, wz = 1: right wheel 2.2 / 0.075 = 29.33 rad/s, the faster one.
  const double scale = wheel_limit_scale(kDocent, 2.0, 1.0, 20.0);
  EXPECT_NEAR(scale, 20.0 / (2.2 / 0.075), 1e-12);
  EXPECT_EQ(wheel_limit_scale(kDocent, 0.3, 0.2, 20.0), 1.0);
  EXPECT_EQ(wheel_limit_scale(kDocent, 0.3, 0.2, 0.0), 0.0);
}

}  // namespace
}  // namespace swivel::differential
