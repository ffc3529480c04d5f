// SPDX-License-Identifier: Apache-2.0
#include "swivel/motion/twist_limiter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "alloc_guard.hpp"

namespace swivel::motion {
namespace {

constexpr double kDt = 0.001;

struct Trace {
  std::vector<double> v;
  std::vector<double> a;
};

// Steps through `targets` (each held for `hold` steps) and records value and acceleration.
Trace run(AxisLimiter& limiter, const std::vector<double>& targets, int hold) {
  Trace t;
  double prev_v = limiter.value();
  double prev_a = 0.0;
  for (double target : targets) {
    for (int k = 0; k < hold; ++k) {
      const double v = limiter.step(target, kDt);
      const double a = (v - prev_v) / kDt;
      t.v.push_back(v);
      t.a.push_back(a);
      prev_v = v;
      prev_a = a;
    }
  }
  (void)prev_a;
  return t;
}

TEST(AxisLimiter, WithoutLimitsFollowsTheTarget) {
  AxisLimiter l;
  EXPECT_FALSE(l.active());
  EXPECT_EQ(l.step(0.7, kDt), 0.7);
  EXPECT_EQ(l.step(-3.0, kDt), -3.0);
}

TEST(AxisLimiter, VelocityAndAccelerationBoundsHold) {
  AxisLimiter l({0.5, 0.6, kNoLimit});
  const Trace t = run(l, {2.0, -2.0, 0.0}, 3000);
  for (std::size_t k = 0; k < t.v.size(); ++k) {
    ASSERT_LE(std::abs(t.v[k]), 0.5 + 1e-12) << k;
    ASSERT_LE(std::abs(t.a[k]), 0.6 + 1e-9) << k;
  }
  EXPECT_NEAR(t.v[2999], 0.5, 1e-12);  // reached the velocity limit
  EXPECT_NEAR(t.v[5999], -0.5, 1e-12);
  EXPECT_EQ(t.v.back(), 0.0);  // and stopped exactly
  // 0.5 m/s at 0.6 m/s^2 takes 0.833 s: still ramping after 0.8 s, there at 0.84 s.
  EXPECT_LT(t.v[799], 0.49);
  EXPECT_NEAR(t.v[839], 0.5, 1e-12);
}

TEST(AxisLimiter, JerkLimitedRampArrivesWithoutOvershoot) {
  const AxisLimits limits{kNoLimit, 1.0, 5.0};
  AxisLimiter l(limits);
  const Trace t = run(l, {0.8, 0.0}, 4000);
  double peak = 0.0;
  for (std::size_t k = 0; k < 4000; ++k) peak = std::max(peak, t.v[k]);
  EXPECT_LE(peak, 0.8 + 1e-9);
  EXPECT_NEAR(t.v[3999], 0.8, 1e-9);
  EXPECT_NEAR(t.v.back(), 0.0, 1e-9);
  for (std::size_t k = 4000; k < t.v.size(); ++k) ASSERT_GE(t.v[k], -1e-9) << k;
  for (std::size_t k = 1; k < t.a.size(); ++k) {
    ASSERT_LE(std::abs(t.a[k]), 1.0 + 1e-9) << k;
    // The acceleration changes by at most j dt per step, except on the final arriving step.
    if (std::abs(t.v[k] - (k < 4000 ? 0.8 : 0.0)) > 1e-12) {
      ASSERT_LE(std::abs(t.a[k] - t.a[k - 1]), 5.0 * kDt + 1e-9) << k;
    }
  }
}

TEST(AxisLimiter, BadInputsDoNotCorruptTheState) {
  AxisLimiter l({1.0, 1.0, kNoLimit});
  l.step(1.0, 0.1);
  const double v = l.value();
  EXPECT_EQ(l.step(1.0, std::nan("")), v);
  EXPECT_EQ(l.step(1.0, -0.1), v);
  EXPECT_NEAR(l.step(std::nan(""), 0.05), v - 0.05, 1e-12);  // a NaN target means stop
}

TEST(TwistLimiter, ReadsTheRobotModelsLimitsPerAxis) {
  MotionLimits limits;
  limits.linear_acceleration_mps2 = 0.5;
  limits.angular_acceleration_radps2 = 2.0;
  limits.angular_velocity_radps = 1.0;
  TwistLimiter l(limits);
  EXPECT_TRUE(l.active());
  Twist2 out;
  for (int k = 0; k < 100; ++k) out = l.step(Twist2{1.0, -1.0, 3.0}, kDt);
  EXPECT_NEAR(out.vx_mps, 0.05, 1e-12);  // 0.1 s at 0.5 m/s^2, each axis on its own
  EXPECT_NEAR(out.vy_mps, -0.05, 1e-12);
  EXPECT_NEAR(out.wz_radps, 0.2, 1e-12);
  for (int k = 0; k < 1000; ++k) out = l.step(Twist2{1.0, -1.0, 3.0}, kDt);
  EXPECT_NEAR(out.wz_radps, 1.0, 1e-12);  // velocity limit
  EXPECT_FALSE(TwistLimiter(MotionLimits{}).active());
}

TEST(TwistLimiter, ContinuesFromAnotherLimitersVelocityAndAcceleration) {
  MotionLimits moving;
  moving.linear_acceleration_mps2 = 1.0;
  moving.linear_jerk_mps3 = 10.0;
  MotionLimits stopping = moving;
  stopping.linear_acceleration_mps2 = 0.5;
  TwistLimiter a(moving);
  TwistLimiter b(stopping);
  for (int k = 0; k < 150; ++k) (void)a.step(Twist2{1.0, 0.0, 0.0}, kDt);
  const double v = a.value().vx_mps;  // still accelerating at 1 m/s^2
  b.continue_from(a);
  EXPECT_EQ(b.value().vx_mps, v);
  // The acceleration came along: it falls at the jerk limit instead of jumping to zero.
  const double next = b.step(Twist2{}, kDt).vx_mps;
  EXPECT_GT(next - v, 0.0);
  EXPECT_NEAR((next - v) / kDt, 1.0 - 10.0 * kDt, 1e-9);
}

TEST(TwistLimiter, StepsWithoutAllocating) {
  MotionLimits limits;
  limits.linear_acceleration_mps2 = 0.5;
  limits.linear_jerk_mps3 = 3.0;
  limits.angular_acceleration_radps2 = 2.0;
  TwistLimiter l(limits);
  test::HeapCounts counts;
  double sum = 0.0;
  {
    test::AllocCounter counter;
    for (int k = 0; k < 20000; ++k) {
      const double s = (k / 2000) % 2 == 0 ? 1.0 : -1.0;
      sum += l.step(Twist2{0.5 * s, 0.2 * s, s}, kDt).vx_mps;
    }
    counts = counter.counts();
  }
  EXPECT_EQ(counts.allocations, 0U);
  EXPECT_EQ(counts.deallocations, 0U);
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
}  // namespace swivel::motion
