// SPDX-License-Identifier: Apache-2.0
// The balance of a caster robot's servos and tyres (caster_forces.hpp), against what friction
// and a servo must do: casters rolling where their servos steer them stay with them; a servo
// short of its yield cannot slide its tyre (at rest it turns its caster only as far as the
// body gives way sideways, every contact gripping), and beyond it drags the tyre across the
// floor at the rate its damping allows; a servo told to steer against the rolling winds up
// until it drags its tyre, and its caster then stays one yield behind.

#include "swivel/sim/caster_forces.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "swivel/sim/world.hpp"
#include "test_support.hpp"

namespace swivel::sim {
namespace {

constexpr double kYieldRad = 0.03;
constexpr double kStepS = 0.005;

struct Robot {
  RobotModel model = test::swpc4();
  CasterForces forces;
  std::array<CasterState, 4> casters{};
  Twist2 previous;
  Twist2 twist;
  std::array<double, 4> rates{};

  Robot() { forces.steering_yield_rad = kYieldRad; }

  bool step() {
    return caster_force_step(forces, model.modules, casters, kStepS, previous, twist, rates);
  }

  // How fast caster i's contact slides across its wheel (its steering at 0, along +x).
  [[nodiscard]] double sideways_slip_mps(std::size_t i) const {
    const SwpcModuleParams& m = model.modules[i];
    const double axis_vy = twist.vy_mps + twist.wz_radps * m.x_m;
    return axis_vy - m.caster_offset_m * (twist.wz_radps + rates[i]);
  }

  // Below this a tyre grips: its force is under its friction.
  [[nodiscard]] double creep_mps() const { return forces.creep_floor_mps / forces.creep_stiffness; }
};

TEST(CasterForces, CastersRollingWhereTheirServosSteerStayWithThem) {
  Robot robot;
  const double speed = 0.3;
  for (std::size_t i = 0; i < 4; ++i) {
    // Pointing along +x: the contact trails the axis as the robot drives that way.
    robot.casters[i].wheel_rate_radps = speed / robot.model.modules[i].wheel_radius_m;
  }
  robot.previous = Twist2{speed, 0.0, 0.0};
  robot.twist = robot.previous;
  ASSERT_TRUE(robot.step());
  EXPECT_NEAR(robot.twist.vx_mps, speed, 1e-6);
  EXPECT_NEAR(robot.twist.vy_mps, 0.0, 1e-6);
  EXPECT_NEAR(robot.twist.wz_radps, 0.0, 1e-6);
  for (const double rate : robot.rates) EXPECT_NEAR(rate, 0.0, 1e-6);
}

TEST(CasterForces, AServoShortOfItsYieldCannotSlideItsTyre) {
  Robot robot;
  robot.casters[0].servo_ref_rad = 0.5 * kYieldRad;
  ASSERT_TRUE(robot.step());
  // The caster turns only as the body gives way sideways under it, every contact gripping.
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_LT(std::abs(robot.sideways_slip_mps(i)), robot.creep_mps()) << i;
  }
  EXPECT_GT(robot.rates[0], 0.0);
  EXPECT_GT(robot.twist.vy_mps, 0.0) << "the body moves the way the turning contact pushes";
}

TEST(CasterForces, BeyondItsYieldTheServoDragsTheCasterAtTheRateItsDampingAllows) {
  Robot robot;
  robot.casters[0].servo_ref_rad = 2.0 * kYieldRad;
  ASSERT_TRUE(robot.step());
  // The tyre slides at its friction: error - h rate + tau (0 - rate) = yield.
  const double expected = (2.0 * kYieldRad - kYieldRad) / (kStepS + robot.forces.servo_damping_s);
  EXPECT_NEAR(robot.rates[0], expected, 0.02 * expected);
  EXPECT_GT(std::abs(robot.sideways_slip_mps(0)), 100.0 * robot.creep_mps());
  for (std::size_t i = 1; i < 4; ++i) {
    EXPECT_LT(std::abs(robot.sideways_slip_mps(i)), robot.creep_mps()) << i;
  }
}

TEST(CasterForces, AServoSteeredAgainstTheRollingWindsUpUntilItDragsItsTyre) {
  const RobotModel model = test::swpc4();
  SimOptions options;
  options.sensor_noise = false;
  options.quantize_encoders = false;
  options.motion_capture = false;
  options.substep_s = kStepS;
  options.caster_forces.steering_yield_rad = kYieldRad;
  World world(model, options);
  const double speed = 0.3;
  const double servo_rate = 0.05;  // module 1 only; the rolling asks for none
  ActuatorCommand command;
  command.module_count = 4;
  for (std::size_t i = 0; i < 4; ++i) {
    command.wheel_rate_radps[i] = speed / model.modules[i].wheel_radius_m;
  }
  command.steer_rate_radps[0] = servo_rate;
  double t = 0.0;
  while (t < 0.2 - 1e-9) {
    ASSERT_EQ(world.step(kStepS, command), Status::kOk);
    t += kStepS;
  }
  // Within its yield the tyre holds the caster back where the rolling keeps it.
  EXPECT_LT(std::abs(world.true_steer_rad(0)), 0.5 * servo_rate * t);
  while (t < 10.0 - 1e-9) {
    ASSERT_EQ(world.step(kStepS, command), Status::kOk);
    t += kStepS;
  }
  // Then the servo drags it, one yield behind its reference.
  const double error = servo_rate * t - world.true_steer_rad(0);
  EXPECT_GT(error, 0.95 * kYieldRad);
  EXPECT_LT(error, 1.05 * kYieldRad);
  EXPECT_NEAR(world.true_steer_rate_radps(0), servo_rate, 0.05 * servo_rate);
  EXPECT_EQ(world.caster_force_failures(), 0U);
}

// The message a world built with `forces` is refused with, "" when it is accepted.
std::string refusal(const CasterForces& forces) {
  SimOptions options;
  options.caster_forces = forces;
  try {
    World world(test::swpc4(), options);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(CasterForces, AYieldThatIsNotANumberOrNegativeIsRefused) {
  for (const double yield :
       {-0.01, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    CasterForces forces;
    forces.steering_yield_rad = yield;
    EXPECT_EQ(refusal(forces), "caster forces: steering_yield_rad must be finite and >= 0")
        << yield;
  }
  CasterForces damping;
  damping.servo_damping_s = 0.0;
  EXPECT_EQ(refusal(damping), "caster forces: servo_damping_s must be finite and positive");
  CasterForces friction;
  friction.friction_coefficient = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(refusal(friction), "caster forces: friction_coefficient must be finite and positive");
  CasterForces rigid;  // the default: off
  EXPECT_EQ(refusal(rigid), "");
}

}  // namespace
}  // namespace swivel::sim
