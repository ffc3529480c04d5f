// SPDX-License-Identifier: Apache-2.0
#include "swivel/swpc/swpc_kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "alloc_guard.hpp"

namespace swivel::swpc {
namespace {

constexpr double kPi = std::numbers::pi;

// The paper's design values (docs/methods.md §1), in metres.
std::vector<SwpcModuleParams> design_modules() {
  return {{0.215, 0.125, 0.0, 0.020, 0.055},
          {0.215, -0.125, 0.0, 0.020, 0.055},
          {-0.215, -0.125, 0.0, 0.020, 0.055},
          {-0.215, 0.125, 0.0, 0.020, 0.055}};
}

std::vector<SwpcModuleParams> random_modules(std::mt19937& rng, std::size_t n) {
  std::uniform_real_distribution<double> pos(-0.6, 0.6);
  std::uniform_real_distribution<double> offset(0.005, 0.06);
  std::uniform_real_distribution<double> radius(0.03, 0.1);
  std::vector<SwpcModuleParams> modules(n);
  for (auto& m : modules) {
    m.x_m = pos(rng);
    m.y_m = pos(rng);
    m.caster_offset_m = offset(rng);
    m.wheel_radius_m = radius(rng);
  }
  return modules;
}

std::vector<double> random_angles(std::mt19937& rng, std::size_t n) {
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::vector<double> phi(n);
  for (auto& p : phi) p = angle(rng);
  return phi;
}

Twist2 random_twist(std::mt19937& rng) {
  std::uniform_real_distribution<double> v(-1.0, 1.0);
  std::uniform_real_distribution<double> w(-2.0, 2.0);
  return {v(rng), v(rng), w(rng)};
}

struct Rates {
  std::vector<double> steer;
  std::vector<double> wheel;
};

Rates inverse_all(const std::vector<SwpcModuleParams>& modules, const std::vector<double>& phi,
                  const Twist2& t) {
  Rates rates;
  for (std::size_t i = 0; i < modules.size(); ++i) {
    const ModuleRates r = inverse_module(modules[i], phi[i], t);
    rates.steer.push_back(r.steer_rate_radps);
    rates.wheel.push_back(r.wheel_rate_radps);
  }
  return rates;
}

TEST(SwpcKinematics, InverseThenForwardRecoversRandomTwistsForTwoToEightModules) {
  std::mt19937 rng(20240601);
  for (std::size_t n = 2; n <= 8; ++n) {
    for (int trial = 0; trial < 200; ++trial) {
      const auto modules = random_modules(rng, n);
      const auto phi = random_angles(rng, n);
      const Twist2 t = random_twist(rng);
      const Rates rates = inverse_all(modules, phi, t);

      const ForwardResult fit = forward(modules, phi, rates.steer, rates.wheel);

      ASSERT_TRUE(fit.ok) << "N = " << n << ", trial " << trial;
      EXPECT_NEAR(fit.twist.vx_mps, t.vx_mps, 1e-9);
      EXPECT_NEAR(fit.twist.vy_mps, t.vy_mps, 1e-9);
      EXPECT_NEAR(fit.twist.wz_radps, t.wz_radps, 1e-9);
      EXPECT_LT(fit.residual, 1e-12);
    }
  }
}

TEST(SwpcKinematics, SixteenModulesRoundTrip) {
  std::mt19937 rng(7);
  const auto modules = random_modules(rng, kMaxModules);
  const auto phi = random_angles(rng, kMaxModules);
  const Twist2 t{0.3, -0.4, 0.9};
  const Rates rates = inverse_all(modules, phi, t);

  const ForwardResult fit = forward(modules, phi, rates.steer, rates.wheel);

  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.twist.vx_mps, 0.3, 1e-10);
  EXPECT_NEAR(fit.twist.vy_mps, -0.4, 1e-10);
  EXPECT_NEAR(fit.twist.wz_radps, 0.9, 1e-10);
}

TEST(SwpcKinematics, ContactPointHasNoLateralVelocityUnderInverseKinematics) {
  std::mt19937 rng(11);
  const auto modules = random_modules(rng, 64);
  for (const auto& m : modules) {
    const double phi = random_angles(rng, 1)[0];
    const Twist2 t = random_twist(rng);
    const ModuleRates rates = inverse_module(m, phi, t);

    double vx = 0.0;
    double vy = 0.0;
    contact_point_velocity(m, phi, rates.steer_rate_radps, t, vx, vy);

    const double lateral = -std::sin(phi) * vx + std::cos(phi) * vy;
    const double along = std::cos(phi) * vx + std::sin(phi) * vy;
    EXPECT_NEAR(lateral, 0.0, 1e-12);
    EXPECT_NEAR(along, m.wheel_radius_m * rates.wheel_rate_radps, 1e-12);
  }
}

// Differentiates the contact point's world position numerically, independently of the
// formulas in the library: robot pose under constant twist, c = p - d u(phi(t)).
TEST(SwpcKinematics, ContactPointVelocityMatchesFiniteDifferenceOfGeometry) {
  std::mt19937 rng(13);
  const auto modules = random_modules(rng, 32);
  for (const auto& m : modules) {
    const double phi0 = random_angles(rng, 1)[0];
    const Twist2 t = random_twist(rng);
    const double steer_rate = std::uniform_real_distribution<double>(-3.0, 3.0)(rng);
    auto contact_world = [&](double time_s) {
      const Pose2 pose = integrate_twist(t, time_s);  // world frame = robot frame at 0
      const double phi = phi0 + steer_rate * time_s;
      const double cx = m.x_m - m.caster_offset_m * std::cos(phi);
      const double cy = m.y_m - m.caster_offset_m * std::sin(phi);
      return std::array<double, 2>{
          pose.x_m + std::cos(pose.yaw_rad) * cx - std::sin(pose.yaw_rad) * cy,
          pose.y_m + std::sin(pose.yaw_rad) * cx + std::cos(pose.yaw_rad) * cy};
    };
    const double h = 1e-5;
    const auto plus = contact_world(h);
    const auto minus = contact_world(-h);

    double vx = 0.0;
    double vy = 0.0;
    contact_point_velocity(m, phi0, steer_rate, t, vx, vy);

    EXPECT_NEAR(vx, (plus[0] - minus[0]) / (2 * h), 1e-7);
    EXPECT_NEAR(vy, (plus[1] - minus[1]) / (2 * h), 1e-7);
  }
}

TEST(SwpcKinematics, ResidualIsZeroForConsistentRatesAndGrowsWithSlip) {
  const auto modules = design_modules();
  const std::vector<double> phi{0.3, -1.2, 2.5, 0.9};
  const Twist2 t{0.2, 0.1, 0.4};
  Rates rates = inverse_all(modules, phi, t);
  const ForwardResult consistent = forward(modules, phi, rates.steer, rates.wheel);

  rates.wheel[1] += 1.0;  // module 2 slips by r * 1 rad/s = 55 mm/s
  const ForwardResult slipping = forward(modules, phi, rates.steer, rates.wheel);
  rates.wheel[1] += 1.0;
  const ForwardResult slipping_twice = forward(modules, phi, rates.steer, rates.wheel);

  ASSERT_TRUE(consistent.ok);
  ASSERT_TRUE(slipping.ok);
  EXPECT_LT(consistent.residual, 1e-14);
  // One bad equation of 8 leaves a share of its 55 mm/s error in the RMS residual.
  EXPECT_GT(slipping.residual, 5e-3);
  EXPECT_LT(slipping.residual, 0.055 / std::sqrt(8.0) + 1e-12);
  // The residual of a linear least-squares fit is linear in the inconsistency.
  EXPECT_NEAR(slipping_twice.residual, 2.0 * slipping.residual, 1e-12);
}

TEST(SwpcKinematics, DegenerateSystemsAreRejected) {
  const std::vector<SwpcModuleParams> one{{0.1, 0.0, 0.0, 0.02, 0.05}};
  const std::vector<double> one_value{0.0};
  EXPECT_FALSE(forward(one, one_value, one_value, one_value).ok);

  // Same point, no caster offset: w never enters the equations.
  const std::vector<SwpcModuleParams> colocated_swerve(3, {0.1, 0.2, 0.0, 0.0, 0.05});
  const std::vector<double> spread{0.0, 2.0, -2.0};
  const std::vector<double> rates{0.1, 0.2, 0.3};
  EXPECT_FALSE(forward(colocated_swerve, spread, rates, rates).ok);

  // Same point and same steering angle: every module writes the same two equations.
  const std::vector<SwpcModuleParams> colocated(3, {0.1, 0.2, 0.0, 0.02, 0.05});
  const std::vector<double> same{0.7, 0.7, 0.7};
  EXPECT_FALSE(forward(colocated, same, rates, rates).ok);

  // With d > 0 and different angles the steering rates do observe w.
  EXPECT_TRUE(forward(colocated, spread, rates, rates).ok);

  const auto modules = design_modules();
  const std::vector<double> four{0.0, 0.0, 0.0, 0.0};
  const std::vector<double> three{0.0, 0.0, 0.0};
  EXPECT_TRUE(forward(modules, four, four, four).ok);
  EXPECT_FALSE(forward(modules, three, four, four).ok);
  std::vector<double> bad = four;
  bad[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(forward(modules, four, bad, four).ok);
  bad[2] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(forward(modules, bad, four, four).ok);

  const std::vector<SwpcModuleParams> too_many(kMaxModules + 1, modules[0]);
  const std::vector<double> zeros(kMaxModules + 1, 0.0);
  EXPECT_FALSE(forward(too_many, zeros, zeros, zeros).ok);
}

TEST(SwpcKinematics, DesaturationKeepsDirectionAndRespectsEveryLimit) {
  std::mt19937 rng(17);
  const double max_wheel = 20.0;
  const double max_steer = 6.0;
  int scaled_count = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const auto modules = random_modules(rng, 4);
    const auto phi = random_angles(rng, 4);
    Twist2 t = random_twist(rng);
    const double s = desaturation_scale(modules, phi, t, max_wheel, max_steer);
    ASSERT_GT(s, 0.0);
    ASSERT_LE(s, 1.0);
    const Twist2 scaled{s * t.vx_mps, s * t.vy_mps, s * t.wz_radps};
    double worst = 0.0;  // largest rate as a fraction of its limit
    for (std::size_t i = 0; i < 4; ++i) {
      const ModuleRates r = inverse_module(modules[i], phi[i], scaled);
      EXPECT_LE(std::abs(r.wheel_rate_radps), max_wheel * (1 + 1e-12));
      EXPECT_LE(std::abs(r.steer_rate_radps), max_steer * (1 + 1e-12));
      worst = std::max({worst, std::abs(r.wheel_rate_radps) / max_wheel,
                        std::abs(r.steer_rate_radps) / max_steer});
    }
    if (s < 1.0) {
      ++scaled_count;
      EXPECT_NEAR(worst, 1.0, 1e-12) << "scaling must stop exactly at the binding limit";
    } else {
      EXPECT_LE(worst, 1.0);
    }
  }
  EXPECT_GT(scaled_count, 50) << "the random twists should exercise the limits";
  EXPECT_EQ(desaturation_scale(design_modules(), std::vector<double>(4, 0.0), Twist2{}, 1.0, 1.0),
            1.0);
  EXPECT_EQ(desaturation_scale(design_modules(), std::vector<double>(4, 0.0), {1, 0, 0}, 0.0, 1.0),
            0.0);
}

TEST(SwpcKinematics, SelfAlignedAngleStopsTheSteeringWithTheWheelRollingForward) {
  std::mt19937 rng(19);
  const auto modules = random_modules(rng, 200);
  int aligned = 0;
  for (const auto& m : modules) {
    const Twist2 t = random_twist(rng);
    double phi = 0.0;
    double vx = 0.0;
    double vy = 0.0;
    steering_axis_velocity(m, t, vx, vy);
    const bool exists = std::hypot(vx, vy) > m.caster_offset_m * std::abs(t.wz_radps);
    ASSERT_EQ(self_aligned_steer_angle(m, t, phi), exists);
    if (!exists) continue;
    ++aligned;
    const ModuleRates r = inverse_module(m, phi, t);
    EXPECT_NEAR(r.steer_rate_radps, 0.0, 1e-9);
    EXPECT_GT(r.wheel_rate_radps, 0.0);
  }
  EXPECT_GT(aligned, 150);

  // Pure translation: the heading of the steering-axis velocity.
  double phi = 0.0;
  ASSERT_TRUE(self_aligned_steer_angle(design_modules()[0], {0.0, -0.3, 0.0}, phi));
  EXPECT_NEAR(phi, -kPi / 2, 1e-15);
  // Turning about the steering axis itself: no steady state.
  const SwpcModuleParams m = design_modules()[0];  // a copy: the vector is a temporary
  EXPECT_FALSE(self_aligned_steer_angle(m, {m.y_m * 0.5, -m.x_m * 0.5, 0.5}, phi));
}

TEST(SwpcKinematics, IntegrateTwistMatchesFineNumericalIntegration) {
  for (const Twist2& t : {Twist2{0.4, -0.2, 1.3}, Twist2{0.4, -0.2, 1e-7}, Twist2{0.0, 0.0, 2.0},
                          Twist2{-0.3, 0.5, -0.05}}) {
    const double dt = 0.7;
    const Pose2 exact = integrate_twist(t, dt);
    // Midpoint rule on the heading: second order, 1e5 steps.
    double x = 0.0;
    double y = 0.0;
    const int steps = 100000;
    const double h = dt / steps;
    for (int k = 0; k < steps; ++k) {
      const double yaw = t.wz_radps * (k + 0.5) * h;
      x += h * (std::cos(yaw) * t.vx_mps - std::sin(yaw) * t.vy_mps);
      y += h * (std::sin(yaw) * t.vx_mps + std::cos(yaw) * t.vy_mps);
    }
    EXPECT_NEAR(exact.x_m, x, 1e-9);
    EXPECT_NEAR(exact.y_m, y, 1e-9);
    EXPECT_DOUBLE_EQ(exact.yaw_rad, t.wz_radps * dt);
  }
  // Both branches agree at the switch-over (the twists differ by one ulp of w).
  const double w_switch = 1e-6;
  const Pose2 below = integrate_twist({0.5, 0.2, std::nextafter(w_switch, 0.0)}, 1.0);
  const Pose2 above = integrate_twist({0.5, 0.2, w_switch}, 1.0);
  EXPECT_NEAR(below.x_m, above.x_m, 1e-15);
  EXPECT_NEAR(below.y_m, above.y_m, 1e-15);
  EXPECT_NEAR(above.y_m, 0.2 + 0.5 * 0.5e-6, 1e-13);
}

TEST(SwpcKinematics, ForwardAndInverseDoNotAllocate) {
  std::mt19937 rng(23);
  const auto modules = random_modules(rng, kMaxModules);
  const auto phi = random_angles(rng, kMaxModules);
  const Rates rates = inverse_all(modules, phi, {0.1, 0.2, 0.3});
  {
    test::AllocCounter probe;
    // Escapes through a volatile pointer: clang may elide an unused new/delete pair.
    auto p = std::make_unique<int>(1);
    int* volatile escaped = p.get();
    (void)escaped;
    ASSERT_GE(probe.counts().allocations, 1U) << "the allocation counter must see operator new";
  }

  // Counts operator new everywhere and, outside sanitizer builds, malloc (Eigen's) too.
  test::AllocCounter guard;
  double sink = 0.0;
  for (int k = 0; k < 1000; ++k) {
    const ForwardResult fit = forward(modules, phi, rates.steer, rates.wheel);
    const ModuleRates r = inverse_module(modules[0], phi[0], fit.twist);
    sink += r.wheel_rate_radps + desaturation_scale(modules, phi, fit.twist, 10.0, 10.0);
  }
  EXPECT_EQ(guard.counts().allocations, 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace swivel::swpc
