// SPDX-License-Identifier: Apache-2.0
#include "swivel/sim/effects.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "swivel/sim/open_loop.hpp"
#include "swivel/sim/world.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"
#include "test_support.hpp"

namespace swivel::sim {
namespace {

using test::docent;
using test::swpc4;

constexpr double kCountRad = 2.0 * std::numbers::pi / 4096.0;

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no exception";
  return "";
}

SimOptions quiet() {
  SimOptions o;
  o.sensor_noise = false;
  return o;
}

ActuatorCommand wheels(double left, double right) {
  ActuatorCommand c;
  c.module_count = 2;
  c.wheel_rate_radps = {left, right};
  return c;
}

TEST(EffectLibrary, ListsTheEffectsOfEachDrivetrain) {
  std::vector<std::string> diff;
  for (const EffectInfo& e : effect_library(docent())) diff.push_back(e.name);
  EXPECT_EQ(diff,
            (std::vector<std::string>{"gyro_bias", "gyro_scale", "wheel_radius", "track_width",
                                      "track_scrub", "slip", "actuator_lag", "sensor_latency"}));
  const auto swpc = effect_library(swpc4());
  const EffectInfo* steer = find_effect(swpc, "steering_offset");
  ASSERT_NE(steer, nullptr);
  ASSERT_EQ(steer->params.size(), 4U);
  EXPECT_EQ(steer->params[3].key, "module_4_rad");
  EXPECT_EQ(steer->params[3].identity, 0.0);
  EXPECT_NE(find_effect(swpc, "caster_offset"), nullptr);
  EXPECT_EQ(find_effect(swpc, "track_width"), nullptr);
}

TEST(EffectLibrary, IdentityValuesChangeNothing) {
  RobotModel model = swpc4();
  for (const EffectInfo& e : effect_library(model)) {
    for (const EffectParamInfo& p : e.params) model.effects[e.name][p.key] = p.identity;
  }
  const PlantParams with = resolve_plant(model);
  const PlantParams without = resolve_plant(swpc4());
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(with.modules[i].wheel_radius_m, without.modules[i].wheel_radius_m);
    EXPECT_EQ(with.modules[i].caster_offset_m, without.modules[i].caster_offset_m);
    EXPECT_EQ(with.modules[i].steering_offset_rad, without.modules[i].steering_offset_rad);
    EXPECT_EQ(with.modules[i].x_m, without.modules[i].x_m);
    EXPECT_EQ(with.modules[i].y_m, without.modules[i].y_m);
  }
  EXPECT_EQ(with.sensors.gyro.bias_rad_s, 0.0);
  EXPECT_EQ(with.sensor_delay_s, 0.0);
}

TEST(EffectLibrary, ErrorsNameEffectAndParameter) {
  RobotModel swpc = swpc4();
  swpc.effects["track_width"]["scale"] = 1.01;
  EXPECT_EQ(message_of([&] { validate_effects(swpc); }),
            "effects.track_width: not available for a swpc robot (available: gyro_bias, "
            "gyro_scale, wheel_radius, caster_offset, steering_offset, module_layout, slip, "
            "actuator_lag, steering_lag, sensor_latency)");
  RobotModel model = docent();
  model.effects["gyro_bias"]["bias"] = 0.1;
  EXPECT_EQ(message_of([&] { validate_effects(model); }),
            "effects.gyro_bias.bias: unknown parameter (expected: bias_rad_s)");
  model = docent();
  model.effects["gyro_scale"]["scale"] = 3.0;
  EXPECT_EQ(message_of([&] { validate_effects(model); }),
            "effects.gyro_scale.scale: 3 is outside [0.5, 2]");
  model = docent();
  model.effects["floor_bumps"] = {};
  EXPECT_NE(
      message_of([&] { validate_effects(model); }).find("effects.floor_bumps: unknown effect"),
      std::string::npos);
}

TEST(EffectLibrary, SetEffectParsesAssignments) {
  RobotModel model = docent();
  set_effect(model, "gyro_bias.bias_rad_s=0.006");
  set_effect(model, "wheel_radius.left_scale=0.99");
  EXPECT_EQ(model.effects["gyro_bias"]["bias_rad_s"], 0.006);
  EXPECT_EQ(model.effects["wheel_radius"]["left_scale"], 0.99);
  EXPECT_EQ(message_of([&] { set_effect(model, "gyro_bias=1"); }),
            "effect 'gyro_bias=1': expected NAME.PARAM=VALUE");
  EXPECT_EQ(message_of([&] { set_effect(model, "gyro_bias.bias_rad_s=fast"); }),
            "effect 'gyro_bias.bias_rad_s=fast': 'fast' is not a number");
  EXPECT_THROW(set_effect(model, "wheel_radius.module_1_scale=1.1"), std::invalid_argument);
  EXPECT_EQ(model.effects.count("wheel_radius"), 1U);  // unchanged by the failed call
  EXPECT_EQ(model.effects["wheel_radius"].count("module_1_scale"), 0U);
}

// Readings after driving `command` for `duration_s` in 10 ms steps.
HardwareState run(const RobotModel& model, const ActuatorCommand& command, double duration_s,
                  Pose2* truth = nullptr) {
  World world(model, quiet());
  HardwareState hw;
  for (int k = 0; k < std::lround(duration_s * 100); ++k) world.step(0.01, command);
  world.read(hw);
  if (truth != nullptr) *truth = world.true_pose();
  return hw;
}

TEST(Effects, GyroBiasAddsToTheReading) {
  RobotModel model = docent();
  model.effects["gyro_bias"]["bias_rad_s"] = 0.006;
  const HardwareState base = run(docent(), wheels(-2.0, 2.0), 1.0);
  const HardwareState biased = run(model, wheels(-2.0, 2.0), 1.0);
  EXPECT_NEAR(biased.gyro_wz_radps - base.gyro_wz_radps, 0.006, 1e-12);
}

TEST(Effects, GyroScaleMultipliesTheReading) {
  RobotModel model = docent();
  model.effects["gyro_scale"]["scale"] = 1.05;
  const HardwareState base = run(docent(), wheels(-2.0, 2.0), 1.0);
  const HardwareState scaled = run(model, wheels(-2.0, 2.0), 1.0);
  EXPECT_NEAR(base.gyro_wz_radps, 2.0 * 2.0 * 0.075 / 0.40, 1e-9);
  EXPECT_NEAR(scaled.gyro_wz_radps, 1.05 * base.gyro_wz_radps, 1e-9);
}

TEST(Effects, SmallerLeftWheelTurnsLeft) {
  RobotModel model = docent();
  model.effects["wheel_radius"]["left_scale"] = 0.98;
  Pose2 truth;
  const HardwareState hw = run(model, wheels(4.0, 4.0), 5.0, &truth);
  EXPECT_NEAR(hw.wheel_angle_rad[0], 20.0, kCountRad);  // encoders see the same rotation
  EXPECT_NEAR(truth.yaw_rad, 0.02 * 0.075 * 20.0 / 0.40, 1e-9);
}

TEST(Effects, WiderTrackTurnsSlower) {
  RobotModel model = docent();
  model.effects["track_width"]["scale"] = 1.05;
  const HardwareState hw = run(model, wheels(-2.0, 2.0), 1.0);
  EXPECT_NEAR(hw.gyro_wz_radps, 2.0 * 2.0 * 0.075 / (0.40 * 1.05), 1e-9);
}

TEST(Effects, TrackScrubWidensTheTrackOnlyAsMuchAsTheRobotTurns) {
  EXPECT_DOUBLE_EQ(spin_share(-2.0, 2.0), 1.0);  // on the spot
  EXPECT_DOUBLE_EQ(spin_share(2.0, 2.0), 0.0);   // straight
  EXPECT_DOUBLE_EQ(spin_share(0.0, 0.0), 0.0);   // at rest
  EXPECT_DOUBLE_EQ(spin_share(0.0, 4.0), 0.5);   // |4 - 0| / (|4 + 0| + |4 - 0|)
  EXPECT_DOUBLE_EQ(spin_share(1.0, 3.0), 1.0 / 3.0);
  RobotModel model = docent();
  model.effects["track_scrub"]["spin_scale"] = 1.04;
  // On the spot the whole factor, on an arc with spin share 1/2 half of it.
  HardwareState hw = run(model, wheels(-2.0, 2.0), 1.0);
  EXPECT_NEAR(hw.gyro_wz_radps, 2.0 * 2.0 * 0.075 / (0.40 * 1.04), 1e-9);
  hw = run(model, wheels(0.0, 4.0), 1.0);
  EXPECT_NEAR(hw.gyro_wz_radps, 4.0 * 0.075 / (0.40 * 1.02), 1e-9);
  // Straight: no turn to scrub.
  Pose2 truth;
  hw = run(model, wheels(3.0, 3.0), 2.0, &truth);
  EXPECT_NEAR(truth.yaw_rad, 0.0, 1e-12);
}

TEST(Effects, SteeringOffsetShiftsTheSteeringEncoder) {
  RobotModel model = swpc4();
  model.effects["steering_offset"]["module_3_rad"] = 0.02;
  SimOptions options = quiet();
  options.initial_steer_rad = {0.5, 0.5, 0.5, 0.5};
  World world(model, options);
  HardwareState hw;
  world.read(hw);
  EXPECT_NEAR(hw.steer_angle_rad[2], 0.5 - 0.02, kCountRad / 2);
  EXPECT_NEAR(hw.steer_angle_rad[1], 0.5, kCountRad / 2);
}

TEST(Effects, LargerCasterOffsetSettlesAFreeCasterFurtherIn) {
  // Free casters self-align at phi = atan2(v_s) - asin(d w / |v_s|): for a counter-clockwise
  // rotation a larger d gives a smaller angle.
  CalibrationMotion motion{0, 0.8, 0.4};
  const auto settled = [&motion](const RobotModel& truth) {
    const OpenLoopController controller(swpc4());
    ActuatorCommand command;
    Twist2 twist;
    EXPECT_TRUE(controller.calibration(motion, command, twist));
    SimOptions options = quiet();
    options.initial_steer_rad = calibration_steer_angles(resolve_plant(truth), motion);
    World world(truth, options);
    for (int k = 0; k < 500; ++k) world.step(0.01, command);
    return world.true_steer_rad(2);
  };
  RobotModel model = swpc4();
  model.effects["caster_offset"]["module_3_scale"] = 1.5;
  const double base = settled(swpc4());
  const double larger = settled(model);
  EXPECT_LT(larger, base - 0.005);
}

TEST(Effects, ModuleLayoutScalesEveryModulePositionAboutTheOrigin) {
  RobotModel model = swpc4();
  model.effects["module_layout"]["lateral_scale"] = 1.02;
  model.effects["module_layout"]["longitudinal_scale"] = 0.99;
  const PlantParams wider = resolve_plant(model);
  const PlantParams nominal = resolve_plant(swpc4());
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(wider.modules[i].x_m, nominal.modules[i].x_m * 0.99) << "module " << i;
    EXPECT_EQ(wider.modules[i].y_m, nominal.modules[i].y_m * 1.02) << "module " << i;
    EXPECT_EQ(wider.modules[i].caster_offset_m, nominal.modules[i].caster_offset_m);
    EXPECT_EQ(wider.modules[i].wheel_radius_m, nominal.modules[i].wheel_radius_m);
  }
  EXPECT_THROW(set_effect(model, "module_layout.lateral_scale=2"), std::invalid_argument);
  RobotModel diff = docent();
  EXPECT_THROW(set_effect(diff, "module_layout.lateral_scale=1.02"), std::invalid_argument);
}

TEST(Effects, WiderModuleLayoutTurnsSlowerOnTheNominalWheelRates) {
  // A turn on the spot commanded with the nominal geometry: modules further from the centre
  // need more wheel travel per radian, so the robot turns less.
  const Twist2 spin{0.0, 0.0, 0.5};
  const auto turned = [&spin](const RobotModel& truth) {
    const OpenLoopController controller(swpc4());
    SimOptions options = quiet();
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_TRUE(
          swpc::self_aligned_steer_angle(swpc4().modules[i], spin, options.initial_steer_rad[i]));
    }
    World world(truth, options);
    HardwareState hw;
    ActuatorCommand command;
    for (int k = 0; k < 200; ++k) {
      world.read(hw);
      controller.velocity(spin, hw, command);
      world.step(0.01, command);
    }
    return world.true_pose().yaw_rad;
  };
  RobotModel model = swpc4();
  model.effects["module_layout"]["lateral_scale"] = 1.2;
  const double base = turned(swpc4());
  const double wider = turned(model);
  EXPECT_NEAR(base, 1.0, 0.01);
  EXPECT_LT(wider, base * 0.97);
}

TEST(Effects, SlipLosesGroundWhileAccelerating) {
  RobotModel model = docent();
  model.effects["slip"]["gain_per_radps2"] = 0.01;
  const auto accelerate = [](const RobotModel& m, Pose2& truth) {
    World world(m, quiet());
    for (int k = 1; k <= 150; ++k) {
      const double rate = 5.0 * std::min(1.0, k / 50.0);  // 0 -> 5 rad/s in 0.5 s, then hold
      world.step(0.01, wheels(rate, rate));
    }
    HardwareState hw;
    world.read(hw);
    truth = world.true_pose();
    return hw;
  };
  Pose2 base;
  Pose2 slipping;
  const HardwareState a = accelerate(docent(), base);
  const HardwareState b = accelerate(model, slipping);
  EXPECT_EQ(a.wheel_angle_rad[0], b.wheel_angle_rad[0]);
  // Ground lost: r g sum(|psi_dot| dpsi_dot) = r g psi_dot^2 / 2 for a ramp to psi_dot.
  const double expected_loss_m = 0.075 * 0.01 * 0.5 * 25.0;
  EXPECT_NEAR(base.x_m - slipping.x_m, expected_loss_m, 0.05 * expected_loss_m);
}

TEST(Effects, ActuatorLagDelaysTheWheels) {
  RobotModel model = docent();
  model.effects["actuator_lag"]["time_constant_s"] = 0.1;
  const HardwareState hw = run(model, wheels(3.0, 3.0), 1.0);
  // First-order response to a step: angle = w (T - tau (1 - exp(-T / tau))).
  EXPECT_NEAR(hw.wheel_angle_rad[0], 3.0 * (1.0 - 0.1 * (1.0 - std::exp(-10.0))), 2e-3);
  EXPECT_LT(hw.wheel_angle_rad[0], 3.0 - 0.25);
}

TEST(Effects, SteeringLagDelaysTheSteeringOnly) {
  RobotModel model = swpc4();
  model.effects["steering_lag"]["time_constant_s"] = 0.1;
  SimOptions options = quiet();
  World world(model, options);
  ActuatorCommand c;
  c.module_count = 4;
  for (std::size_t i = 0; i < 4; ++i) {
    c.wheel_rate_radps[i] = 2.0;
    c.steer_rate_radps[i] = 1.0;
  }
  world.step(1.0, c);
  // First-order response of the steering rate to a step; the wheels follow at once.
  EXPECT_NEAR(world.true_steer_rad(0), 1.0 - 0.1 * (1.0 - std::exp(-10.0)), 2e-3);
  EXPECT_NEAR(world.true_wheel_rad(0), 2.0, 1e-9);
  EXPECT_EQ(resolve_plant(model).actuator_time_constant_s, 0.0);
  model.effects["actuator_lag"]["time_constant_s"] = 0.05;
  model.effects.erase("steering_lag");
  EXPECT_EQ(resolve_plant(model).steering_time_constant_s, 0.05);  // follows the actuators
}

TEST(Effects, SensorLatencyDelaysEncodersAndGyroButNotMotionCapture) {
  RobotModel model = docent();
  model.effects["sensor_latency"]["delay_s"] = 0.05;
  World world(model, quiet());
  HardwareState hw;
  for (int k = 0; k < 100; ++k) {
    world.step(0.01, wheels(2.0, 4.0));
    world.read(hw);
  }
  EXPECT_NEAR(hw.wheel_angle_rad[1], 4.0 * 0.95, kCountRad);
  EXPECT_NEAR(world.true_wheel_rad(1), 4.0, 1e-9);
  ASSERT_TRUE(hw.motion_capture.valid);
  EXPECT_NEAR(hw.motion_capture.pose.x_m, world.true_pose().x_m, 1e-12);
  // Right after a start the gyro still shows rest: stop, restart and read within the delay.
  World fresh(model, quiet());
  fresh.read(hw);
  fresh.step(0.02, wheels(2.0, 4.0));
  fresh.read(hw);
  EXPECT_NEAR(hw.gyro_wz_radps, 0.0, 1e-12);
  fresh.step(0.1, wheels(2.0, 4.0));
  fresh.read(hw);
  EXPECT_GT(hw.gyro_wz_radps, 0.5 * (4.0 - 2.0) * 0.075 / 0.40);
}

}  // namespace
}  // namespace swivel::sim
