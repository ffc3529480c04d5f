// SPDX-License-Identifier: Apache-2.0
// The calibration motion of docs/methods.md §1 in the simulated world.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "swivel/sim/open_loop.hpp"
#include "swivel/sim/world.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"
#include "test_support.hpp"

namespace swivel::sim {
namespace {

using test::swpc4;
using test::wrap;

RobotModel perturbed_truth() {
  RobotModel truth = swpc4();
  const double dx[] = {0.0012, 0.0015, -0.0012, -0.0017};
  const double delta[] = {0.011, 0.027, 0.017, 0.021};
  const double d[] = {0.0204, 0.0202, 0.0203, 0.0203};
  const double r[] = {0.0544, 0.0547, 0.0560, 0.0557};
  for (int i = 0; i < 4; ++i) {
    truth.modules[i].x_m += dx[i];
    truth.modules[i].y_m -= 0.5 * dx[i];
    truth.modules[i].steering_offset_rad = delta[i];
    truth.modules[i].caster_offset_m = d[i];
    truth.modules[i].wheel_radius_m = r[i];
  }
  return truth;
}

class CalibrationMotionTest : public ::testing::TestWithParam<int> {};

TEST_P(CalibrationMotionTest, RobotTurnsAboutTheLockedContactAndCastersSelfAlign) {
  const auto locked = static_cast<std::size_t>(GetParam());
  const RobotModel nominal = swpc4();
  const RobotModel truth = perturbed_truth();
  const CalibrationMotion motion{locked, 45.0 * std::numbers::pi / 180.0, 0.3};
  const OpenLoopController controller(nominal);
  ActuatorCommand command;
  Twist2 commanded;
  ASSERT_TRUE(controller.calibration(motion, command, commanded));
  EXPECT_EQ(command.mode[locked], ModuleDriveMode::kLocked);

  SimOptions options;
  options.sensor_noise = false;
  options.start_pose = Pose2{1.0, -0.5, 0.4};
  // The locked module at its angle; the free casters deliberately 0.3 rad off alignment.
  options.initial_steer_rad = calibration_steer_angles(resolve_plant(truth), motion);
  for (std::size_t i = 0; i < 4; ++i) {
    if (i != locked) options.initial_steer_rad[i] += 0.3;
  }
  World world(truth, options);
  HardwareState start;
  world.read(start);
  const Pose2 pivot = world.contact_point_world(locked);
  const double radius =
      std::hypot(options.start_pose.x_m - pivot.x_m, options.start_pose.y_m - pivot.y_m);
  EXPECT_GT(radius, 0.2);

  double yaw = options.start_pose.yaw_rad;
  double previous_yaw = world.true_pose().yaw_rad;
  HardwareState hw;
  for (int k = 0; k < 2000; ++k) {  // 20 s
    ASSERT_EQ(world.step(0.01, command), Status::kOk);
    const Pose2& p = world.true_pose();
    yaw += wrap(p.yaw_rad - previous_yaw);
    previous_yaw = p.yaw_rad;
    // The locked contact point stays put and the origin stays on its circle.
    const Pose2 c = world.contact_point_world(locked);
    ASSERT_NEAR(c.x_m, pivot.x_m, 1e-9);
    ASSERT_NEAR(c.y_m, pivot.y_m, 1e-9);
    ASSERT_NEAR(std::hypot(p.x_m - pivot.x_m, p.y_m - pivot.y_m), radius, 1e-9);
  }
  world.read(hw);
  // Locked encoders do not move; the robot turned counter-clockwise.
  EXPECT_EQ(hw.wheel_angle_rad[locked], start.wheel_angle_rad[locked]);
  EXPECT_EQ(hw.steer_angle_rad[locked], start.steer_angle_rad[locked]);
  EXPECT_NEAR(hw.steer_angle_rad[locked], motion.locked_steer_meas_rad,
              2.0 * std::numbers::pi / 4096.0);
  EXPECT_GT(yaw - options.start_pose.yaw_rad, 3.0);

  // Every free caster has settled at its no-slip (self-aligned) angle for the true twist.
  const Twist2 twist = world.true_twist();
  EXPECT_NEAR(twist.wz_radps, 0.3, 0.03);  // nominal wheel rates on the true robot
  for (std::size_t i = 0; i < 4; ++i) {
    if (i == locked) continue;
    double expected = 0.0;
    ASSERT_TRUE(swpc::self_aligned_steer_angle(truth.modules[i], twist, expected));
    EXPECT_NEAR(wrap(world.true_steer_rad(i) - expected), 0.0, 1e-6) << "module " << i + 1;
    EXPECT_NEAR(world.true_steer_rate_radps(i), 0.0, 1e-6);
  }
}

INSTANTIATE_TEST_SUITE_P(EveryModuleLocked, CalibrationMotionTest, ::testing::Values(0, 1, 2, 3));

// The paper's drive: torque-driven wheels roll as the rotation asks (no slip), whatever
// rates the nominal model would have commanded; velocity-tracked ones slip against each other.
TEST(CalibrationMotion, TorqueDrivenWheelsRollWithoutSlipVelocityTrackedOnesSlip) {
  const RobotModel nominal = swpc4();
  const RobotModel truth = perturbed_truth();
  const CalibrationMotion motion{0, 45.0 * std::numbers::pi / 180.0, 0.3};
  const OpenLoopController controller(nominal);
  ActuatorCommand command;
  Twist2 commanded;
  ASSERT_TRUE(controller.calibration(motion, command, commanded));
  double worst_slip[2] = {0.0, 0.0};  // |r dpsi - L dtheta| / (L dtheta): torque, velocity
  for (int torque = 0; torque < 2; ++torque) {
    for (std::size_t i = 1; i < 4; ++i) {
      command.mode[i] = torque == 1 ? ModuleDriveMode::kTorque : ModuleDriveMode::kFreeSteer;
    }
    SimOptions options;
    options.sensor_noise = false;
    options.initial_steer_rad = calibration_steer_angles(resolve_plant(truth), motion);
    World world(truth, options);
    const Pose2 pivot = world.contact_point_world(0);
    std::array<double, 4> lever{};
    std::array<double, 4> psi0{};
    for (std::size_t i = 1; i < 4; ++i) {
      const Pose2 c = world.contact_point_world(i);
      lever[i] = std::hypot(c.x_m - pivot.x_m, c.y_m - pivot.y_m);
      psi0[i] = world.true_wheel_rad(i);
    }
    const double yaw0 = world.true_pose().yaw_rad;
    world.step(2.0, command);
    const double turned = std::abs(world.true_pose().yaw_rad - yaw0);
    ASSERT_GT(turned, 0.3);
    for (std::size_t i = 1; i < 4; ++i) {
      const double rolled = truth.modules[i].wheel_radius_m * (world.true_wheel_rad(i) - psi0[i]);
      const double arc = lever[i] * turned;
      worst_slip[torque == 1 ? 0 : 1] =
          std::max(worst_slip[torque == 1 ? 0 : 1], std::abs(std::abs(rolled) - arc) / arc);
    }
  }
  EXPECT_LT(worst_slip[0], 1e-4);  // torque: the encoders measure the arcs
  EXPECT_GT(worst_slip[1], 1e-3);  // velocity: commanded with the design radii, they slip
}

TEST(CalibrationMotion, TwoLockedModulesHoldTheRobot) {
  const RobotModel model = swpc4();
  SimOptions options;
  options.sensor_noise = false;
  World world(model, options);
  ActuatorCommand command;
  command.module_count = 4;
  command.mode = {ModuleDriveMode::kLocked, ModuleDriveMode::kLocked, ModuleDriveMode::kFreeSteer,
                  ModuleDriveMode::kFreeSteer};
  command.wheel_rate_radps = {0.0, 0.0, 3.0, 3.0};
  world.step(1.0, command);
  EXPECT_EQ(world.true_pose().x_m, 0.0);
  EXPECT_EQ(world.true_pose().yaw_rad, 0.0);
}

TEST(CalibrationMotion, ImpossiblePivotIsRefused) {
  // A module whose steering axis lies within its caster offset of the pivot cannot align.
  RobotModel model = swpc4();
  model.modules[1].x_m = model.modules[0].x_m - 0.03;
  model.modules[1].y_m = model.modules[0].y_m;
  const OpenLoopController controller(model);
  ActuatorCommand command;
  Twist2 twist;
  EXPECT_FALSE(controller.calibration(CalibrationMotion{0, 0.0, 0.3}, command, twist));
  EXPECT_FALSE(controller.calibration(CalibrationMotion{7, 0.0, 0.3}, command, twist));
}

}  // namespace
}  // namespace swivel::sim
