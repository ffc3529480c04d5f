// SPDX-License-Identifier: Apache-2.0
// The generator's own kinematics against docs/methods.md's equations and against geometry.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>

#include "swivel/independent/differential_kinematics.hpp"
#include "swivel/independent/nominal_robots.hpp"
#include "swivel/independent/swpc_kinematics.hpp"

namespace swivel::independent {
namespace {

// The contact point of a module in the world, for a body at (x, y, yaw) and steering phi.
std::array<double, 2> contact_in_world(const SwpcModule& m, double x, double y, double yaw,
                                       double phi) {
  const double px = m.x_m - m.caster_offset_m * std::cos(phi);
  const double py = m.y_m - m.caster_offset_m * std::sin(phi);
  return {x + std::cos(yaw) * px - std::sin(yaw) * py, y + std::sin(yaw) * px + std::cos(yaw) * py};
}

TEST(DifferentialKinematics, InverseGivesTheWheelRatesOfPapersEquations) {
  const WheelPairRates r = differential_inverse(docent_nominal(), 0.3, 0.5);
  // (v -+ w b / 2) / r = (0.3 -+ 0.1) / 0.075
  EXPECT_NEAR(r.left_radps, 0.2 / 0.075, 1e-12);
  EXPECT_NEAR(r.right_radps, 0.4 / 0.075, 1e-12);
}

TEST(DifferentialKinematics, ForwardUndoesInverseWithTheSameGeometry) {
  const DifferentialGeometry g{0.07, 0.08, 0.43};
  const WheelPairRates r = differential_inverse(g, -0.21, 0.77);
  const Twist t = differential_forward(r.left_radps * g.wheel_radius_left_m,
                                       r.right_radps * g.wheel_radius_right_m, g.track_width_m);
  EXPECT_NEAR(t.vx_mps, -0.21, 1e-12);
  EXPECT_NEAR(t.vy_mps, 0.0, 1e-12);
  EXPECT_NEAR(t.wz_radps, 0.77, 1e-12);
}

// The inverse kinematics must make the contact point roll along the wheel at r psi_dot and
// never slide sideways: checked by moving body and steering a little and differencing the
// contact point's world position, independently of the formulas in the code.
TEST(SwpcKinematics, InverseMakesTheContactPointRollWithoutSideSlip) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const SwpcModule m{0.2 * u(rng), 0.2 * u(rng), 0.0, 0.015 + 0.01 * (u(rng) + 1.0),
                       0.05 + 0.01 * (u(rng) + 1.0)};
    const Twist body{0.4 * u(rng), 0.4 * u(rng), 1.0 * u(rng)};
    const double phi = 3.14 * u(rng);
    const double yaw = 3.14 * u(rng);
    const ModuleRates rates = swpc_inverse(m, phi, body);

    const double h = 1e-6;
    const double vx_world = std::cos(yaw) * body.vx_mps - std::sin(yaw) * body.vy_mps;
    const double vy_world = std::sin(yaw) * body.vx_mps + std::cos(yaw) * body.vy_mps;
    const auto a = contact_in_world(m, -h * vx_world, -h * vy_world, yaw - h * body.wz_radps,
                                    phi - h * rates.steer_radps);
    const auto b = contact_in_world(m, h * vx_world, h * vy_world, yaw + h * body.wz_radps,
                                    phi + h * rates.steer_radps);
    const double cx = (b[0] - a[0]) / (2.0 * h);
    const double cy = (b[1] - a[1]) / (2.0 * h);
    const double heading = yaw + phi;  // wheel heading in the world
    const double along = std::cos(heading) * cx + std::sin(heading) * cy;
    const double across = -std::sin(heading) * cx + std::cos(heading) * cy;
    EXPECT_NEAR(along, m.wheel_radius_m * rates.wheel_radps, 1e-6) << "trial " << trial;
    EXPECT_NEAR(across, 0.0, 1e-6) << "trial " << trial;
  }
}

TEST(SwpcKinematics, ForwardUndoesInverseAtAnySteeringAngles) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<SwpcModule, 4> modules = swpc4_nominal();
  for (int trial = 0; trial < 200; ++trial) {
    for (SwpcModule& m : modules) {  // within +-30 % of the design values, as Table 3
      m.caster_offset_m = 0.020 * (1.0 + 0.3 * u(rng));
      m.wheel_radius_m = 0.055 * (1.0 + 0.3 * u(rng));
    }
    const Twist body{0.5 * u(rng), 0.5 * u(rng), 1.0 * u(rng)};
    std::array<double, 4> phi{};
    std::array<double, 4> rolling{};
    std::array<double, 4> steer{};
    for (std::size_t i = 0; i < 4; ++i) {
      phi[i] = 3.14 * u(rng);
      const ModuleRates r = swpc_inverse(modules[i], phi[i], body);
      rolling[i] = modules[i].wheel_radius_m * r.wheel_radps;
      steer[i] = r.steer_radps;
    }
    const Twist back = swpc_forward(modules, phi, rolling, steer);
    EXPECT_NEAR(back.vx_mps, body.vx_mps, 1e-10) << "trial " << trial;
    EXPECT_NEAR(back.vy_mps, body.vy_mps, 1e-10) << "trial " << trial;
    EXPECT_NEAR(back.wz_radps, body.wz_radps, 1e-10) << "trial " << trial;

    // The rolling equations alone agree where the casters are spread out.
    const Twist rolled = swpc_forward_rolling(modules, phi, rolling, Twist{}, 1e-12);
    EXPECT_NEAR(rolled.vx_mps, body.vx_mps, 1e-6) << "trial " << trial;
    EXPECT_NEAR(rolled.wz_radps, body.wz_radps, 1e-6) << "trial " << trial;
  }
}

TEST(SwpcKinematics, ForwardIsTheLeastSquaresCompromiseOfInconsistentModules) {
  const std::array<SwpcModule, 4> modules = swpc4_nominal();
  const std::array<double, 4> phi{0.0, 0.0, 0.0, 0.0};
  // Three wheels roll at 0.2 m/s, one at 0.3: forward speed is their mean, and the faster
  // front-right wheel (module 2, y < 0) turns the body to the left.
  const std::array<double, 4> rolling{0.2, 0.3, 0.2, 0.2};
  const std::array<double, 4> steer{0.0, 0.0, 0.0, 0.0};
  const Twist t = swpc_forward(modules, phi, rolling, steer);
  EXPECT_GT(t.wz_radps, 0.0);
  EXPECT_NEAR(t.vx_mps, 0.225, 0.01);
}

TEST(SwpcKinematics, PassiveCastersAlignedSidewaysNeedNoSteering) {
  const SwpcModule m = swpc4_nominal()[0];
  EXPECT_NEAR(swpc_passive_steer_rate(m, std::numbers::pi / 2, Twist{0.0, 0.3, 0.0}), 0.0, 1e-12);
  // Misaligned by a small angle a, a trailing caster turns back towards the motion at v a / d.
  EXPECT_NEAR(swpc_passive_steer_rate(m, std::numbers::pi / 2 - 0.01, Twist{0.0, 0.3, 0.0}),
              0.3 * std::sin(0.01) / 0.020, 1e-9);
}

TEST(SwpcKinematics, RollingAloneLeavesSidewaysToThePriorAcrossParallelCasters) {
  const std::array<SwpcModule, 4> modules = swpc4_nominal();
  const std::array<double, 4> phi{0.0, 0.0, 0.0, 0.0};
  const std::array<double, 4> rolling{0.25, 0.25, 0.25, 0.25};
  const Twist t = swpc_forward_rolling(modules, phi, rolling, Twist{0.25, 0.07, 0.0}, 1e-3);
  EXPECT_NEAR(t.vx_mps, 0.25, 1e-9);
  EXPECT_NEAR(t.vy_mps, 0.07, 1e-9);
  EXPECT_NEAR(t.wz_radps, 0.0, 1e-9);
}

}  // namespace
}  // namespace swivel::independent
