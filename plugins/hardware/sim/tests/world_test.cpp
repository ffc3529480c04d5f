// SPDX-License-Identifier: Apache-2.0
#include "swivel/sim/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "swivel/sim/open_loop.hpp"
#include "test_support.hpp"

namespace swivel::sim {
namespace {

using test::docent;
using test::Odometry;
using test::swpc4;
using test::wrap;

constexpr double kRateHz = 100.0;
constexpr double kCountsRad = 2.0 * std::numbers::pi / 4096.0;  // one encoder count

SimOptions quiet(bool quantize = true) {
  SimOptions o;
  o.sensor_noise = false;
  o.quantize_encoders = quantize;
  return o;
}

struct RunResult {
  Pose2 odometry;
  Pose2 truth;
  double truth_yaw_unwrapped = 0.0;
  double path_m = 0.0;
  HardwareState last;
};

// Drives `world` open-loop at kRateHz with the nominal model and integrates odometry.
RunResult drive(World& world, const RobotModel& nominal, double duration_s,
                const std::function<Twist2(double)>& profile) {
  const OpenLoopController controller(nominal);
  Odometry odometry(nominal, world.true_pose());
  HardwareState prev;
  HardwareState cur;
  world.read(prev);
  ActuatorCommand command;
  RunResult r;
  double yaw = world.true_pose().yaw_rad;
  const auto steps = static_cast<int>(std::lround(duration_s * kRateHz));
  for (int k = 0; k < steps; ++k) {
    controller.velocity(profile(k / kRateHz), prev, command);
    const Pose2 before = world.true_pose();
    EXPECT_EQ(world.step(1.0 / kRateHz, command), Status::kOk);
    world.read(cur);
    odometry.update(prev, cur);
    const Pose2& after = world.true_pose();
    r.path_m += std::hypot(after.x_m - before.x_m, after.y_m - before.y_m);
    yaw += wrap(after.yaw_rad - before.yaw_rad);
    prev = cur;
  }
  r.odometry = odometry.pose();
  r.truth = world.true_pose();
  r.truth_yaw_unwrapped = yaw;
  r.last = cur;
  return r;
}

double ramp(double t) { return std::min(1.0, t / 0.5); }

Twist2 arc_and_turns(double t) {
  // Forward, then a left arc, then a right turn while slowing: curvature changes sign.
  const double k = ramp(t);
  if (t < 4.0) return {0.3 * k, 0.0, 0.0};
  if (t < 10.0) return {0.3, 0.0, 0.4};
  return {0.15, 0.0, -0.6};
}

TEST(WorldDifferential, NominalOdometryMatchesTruthExactlyWithoutQuantization) {
  const RobotModel model = docent();
  World world(model, quiet(false));
  const RunResult r = drive(world, model, 15.0, arc_and_turns);
  // Piecewise-constant wheel rates make exact arcs in both the world and the odometry.
  EXPECT_NEAR(r.odometry.x_m, r.truth.x_m, 1e-9);
  EXPECT_NEAR(r.odometry.y_m, r.truth.y_m, 1e-9);
  EXPECT_NEAR(wrap(r.odometry.yaw_rad - r.truth.yaw_rad), 0.0, 1e-9);
  EXPECT_GT(r.path_m, 3.5);
}

TEST(WorldDifferential, NominalOdometryMatchesTruthWithinQuantization) {
  const RobotModel model = docent();
  World world(model, quiet(true));
  const RunResult r = drive(world, model, 15.0, arc_and_turns);
  // Counts are cumulative, so quantization does not accumulate: heading error stays below
  // one count of wheel travel over the track (r q / b = 2.9e-4 rad), and position error
  // below that heading error times the path length plus one count of travel.
  const double heading_bound = 0.075 * kCountsRad / 0.40;
  EXPECT_NEAR(wrap(r.odometry.yaw_rad - r.truth.yaw_rad), 0.0, heading_bound);
  const double position_bound = heading_bound * r.path_m + 0.075 * kCountsRad;
  EXPECT_LT(std::hypot(r.odometry.x_m - r.truth.x_m, r.odometry.y_m - r.truth.y_m), position_bound);
}

TEST(WorldDifferential, RightWheelRadiusErrorTurnsLeftByTheExpectedAmount) {
  const RobotModel nominal = docent();
  RobotModel truth = nominal;
  truth.effects["wheel_radius"]["right_scale"] = 1.01;
  World world(truth, quiet(false));
  const RunResult r = drive(world, nominal, 10.0, [](double) { return Twist2{0.3, 0.0, 0.0}; });
  EXPECT_NEAR(r.odometry.yaw_rad, 0.0, 1e-12);  // nominal odometry believes it went straight
  // The right wheel covers 1 % more: yaw = 0.01 r psi_R / b, counter-clockwise.
  const double expected_yaw = 0.01 * 0.075 * r.last.wheel_angle_rad[1] / 0.40;
  EXPECT_GT(expected_yaw, 0.07);
  EXPECT_NEAR(r.truth_yaw_unwrapped, expected_yaw, 1e-9);
  EXPECT_GT(r.truth.y_m, 0.1);  // drifted to the left
}

TEST(WorldSwpc, NominalOdometryMatchesTruthAlongACurvedPath) {
  const RobotModel model = swpc4();
  const auto profile = [](double t) {
    const double k = ramp(t);
    return Twist2{0.25 * k, 0.10 * k * std::cos(0.3 * t), 0.3 * k * std::sin(0.2 * t)};
  };
  for (const bool quantize : {false, true}) {
    SimOptions options = quiet(quantize);
    options.initial_steer_rad = aligned_steer_angles(resolve_plant(model), profile(0.5));
    World world(model, options);
    const RunResult r = drive(world, model, 20.0, profile);
    // Without quantization only the sampling of the steering angles (mid-interval in the
    // odometry, continuous in the world) separates the two, ~3e-5 of the path. One count of
    // wheel travel is 8e-5 m and one count of steering 1.5e-3 rad; cumulative counts and the
    // fit over four modules keep quantization from accumulating: it adds < 0.5 mm here.
    const double bound_m = 1e-4 * r.path_m + (quantize ? 5e-4 : 0.0);
    SCOPED_TRACE(quantize ? "quantized" : "exact encoders");
    EXPECT_GT(r.path_m, 4.0);
    EXPECT_LT(std::hypot(r.odometry.x_m - r.truth.x_m, r.odometry.y_m - r.truth.y_m), bound_m);
    EXPECT_NEAR(wrap(r.odometry.yaw_rad - r.truth.yaw_rad), 0.0, 2e-4);
  }
}

TEST(WorldSwpc, LargerTrueWheelsDriveFurtherThanOdometrySays) {
  const RobotModel nominal = swpc4();
  RobotModel truth = nominal;
  for (int i = 1; i <= 4; ++i)
    truth.effects["wheel_radius"]["module_" + std::to_string(i) + "_scale"] = 1.02;
  World world(truth, quiet(false));
  const RunResult r = drive(world, nominal, 10.0, [](double) { return Twist2{0.3, 0.0, 0.0}; });
  EXPECT_NEAR(r.odometry.x_m, 3.0, 1e-6);
  EXPECT_NEAR(r.truth.x_m / r.odometry.x_m, 1.02, 1e-6);
  EXPECT_NEAR(r.truth.y_m, 0.0, 1e-9);
}

TEST(WorldSwpc, TrueGeometryDifferentFromNominalDrifts) {
  const RobotModel nominal = swpc4();
  RobotModel truth = nominal;
  truth.modules[0].x_m += 0.004;
  truth.modules[2].y_m -= 0.003;
  truth.modules[1].caster_offset_m = 0.0215;
  truth.modules[3].wheel_radius_m = 0.0558;
  World world(truth, quiet(true));
  const RunResult r = drive(world, nominal, 20.0, [](double t) {
    return Twist2{0.2 * ramp(t), 0.0, 0.25 * ramp(t)};
  });
  // Millimetre errors in the geometry: centimetres of drift over a few metres.
  EXPECT_GT(std::hypot(r.odometry.x_m - r.truth.x_m, r.odometry.y_m - r.truth.y_m), 0.01);
}

TEST(WorldSwpc, SteeringEncoderReadsTrueMinusOffset) {
  RobotModel truth = swpc4();
  truth.modules[1].steering_offset_rad = 0.05;
  SimOptions options = quiet(true);
  options.initial_steer_rad = {0.3, 0.7, -1.1, 2.0};
  World world(truth, options);
  HardwareState hw;
  world.read(hw);
  EXPECT_NEAR(hw.steer_angle_rad[0], 0.3, kCountsRad / 2);
  EXPECT_NEAR(hw.steer_angle_rad[1], 0.7 - 0.05, kCountsRad / 2);
  EXPECT_NEAR(hw.steer_angle_rad[3], 2.0, kCountsRad / 2);
  // Quantized to whole counts.
  EXPECT_NEAR(std::remainder(hw.steer_angle_rad[2] / kCountsRad, 1.0), 0.0, 1e-9);
}

TEST(World, GyroNoiseHasTheModelsStandardDeviation) {
  RobotModel model = docent();
  model.sensors.gyro.noise_rad_s = 0.01;
  SimOptions options;
  options.seed = 7;
  World world(model, options);
  ActuatorCommand stop;
  stop.module_count = 2;
  HardwareState hw;
  double sum = 0.0;
  double sum2 = 0.0;
  constexpr int kSamples = 4000;
  for (int k = 0; k < kSamples; ++k) {
    world.step(0.01, stop);
    world.read(hw);
    sum += hw.gyro_wz_radps;
    sum2 += hw.gyro_wz_radps * hw.gyro_wz_radps;
  }
  const double mean = sum / kSamples;
  const double sd = std::sqrt(sum2 / kSamples - mean * mean);
  EXPECT_NEAR(mean, 0.0, 4.0 * 0.01 / std::sqrt(kSamples));
  EXPECT_NEAR(sd, 0.01, 0.001);  // ~4.5 sigma of the sample deviation's spread
}

TEST(World, MotionCaptureArrivesAtItsRate) {
  RobotModel model = docent();
  model.sensors.motion_capture.rate_hz = 100.0;
  World world(model, quiet());
  ActuatorCommand go;
  go.module_count = 2;
  go.wheel_rate_radps = {2.0, 3.0};
  HardwareState hw;
  world.read(hw);
  EXPECT_TRUE(hw.motion_capture.valid);  // t = 0
  int samples = 0;
  for (int k = 0; k < 1000; ++k) {  // 1 kHz reads for 1 s
    world.step(0.001, go);
    world.read(hw);
    if (hw.motion_capture.valid) {
      ++samples;
      EXPECT_NEAR(hw.motion_capture.pose.x_m, world.true_pose().x_m, 1e-12);
      EXPECT_NEAR(hw.motion_capture.stamp_s, hw.stamp_s, 1e-12);
    }
  }
  EXPECT_EQ(samples, 100);
}

TEST(World, MotionCaptureCanBeSwitchedOff) {
  SimOptions options = quiet();
  options.motion_capture = false;
  World world(docent(), options);
  ActuatorCommand stop;
  stop.module_count = 2;
  HardwareState hw;
  for (int k = 0; k < 50; ++k) {
    world.step(0.01, stop);
    world.read(hw);
    EXPECT_FALSE(hw.motion_capture.valid);
  }
}

// With the body held still, the actuators (encoders, lags, latency) read exactly as with it
// moving, in velocity mode.
TEST(World, ActuatorsRunTheSameWithTheBodyHeldStill) {
  RobotModel model = swpc4();
  model.effects["actuator_lag"]["time_constant_s"] = 0.05;
  model.effects["sensor_latency"]["delay_s"] = 0.02;
  SimOptions moving = quiet(false);
  SimOptions still = moving;
  still.move_body = false;
  World a(model, moving);
  World b(model, still);
  const OpenLoopController controller(model);
  HardwareState ha;
  HardwareState hb;
  ActuatorCommand command;
  for (int k = 0; k < 300; ++k) {
    a.read(ha);
    b.read(hb);
    for (std::size_t i = 0; i < 4; ++i) {
      ASSERT_EQ(ha.wheel_angle_rad[i], hb.wheel_angle_rad[i]) << k;
      ASSERT_EQ(ha.steer_angle_rad[i], hb.steer_angle_rad[i]) << k;
      // The encoder as a controller between readings sees it: late by the latency too.
      ASSERT_EQ(b.steer_reading_rad(i), hb.steer_angle_rad[i]) << k;
      // And the angle behind it, before offset and quantization.
      ASSERT_NEAR(b.sensed_steer_rad(i) - model.modules[i].steering_offset_rad,
                  hb.steer_angle_rad[i],
                  2.0 * std::numbers::pi / model.sensors.steering_encoder_counts_per_rev)
          << k;
    }
    controller.velocity(Twist2{0.3, 0.1 * std::sin(0.05 * k), 0.2}, ha, command);
    a.step(0.01, command);
    b.step(0.01, command);
  }
  EXPECT_GT(a.true_pose().x_m, 0.5);
  EXPECT_EQ(b.true_pose().x_m, 0.0);
}

std::vector<double> record(std::uint64_t seed, bool nonsystematic) {
  RobotModel model = swpc4();
  SimOptions options;
  options.seed = seed;
  if (nonsystematic) {
    options.nonsystematic.wheel_slip_std = 0.02;
    options.nonsystematic.lateral_scrub_std = 0.02;
  }
  World world(model, options);
  const OpenLoopController controller(model);
  HardwareState hw;
  ActuatorCommand command;
  std::vector<double> out;
  for (int k = 0; k < 300; ++k) {
    world.read(hw);
    controller.velocity(Twist2{0.2, 0.05, 0.2}, hw, command);
    world.step(0.01, command);
    out.push_back(hw.gyro_wz_radps);
    out.push_back(hw.wheel_angle_rad[2]);
    out.push_back(hw.motion_capture.valid ? hw.motion_capture.pose.x_m : -1.0);
    out.push_back(world.true_pose().y_m);
  }
  return out;
}

TEST(World, SameSeedSameOutputDifferentSeedDifferentOutput) {
  EXPECT_EQ(record(42, true), record(42, true));
  EXPECT_NE(record(42, true), record(43, true));
  EXPECT_EQ(record(42, false), record(42, false));
}

TEST(World, NonSystematicErrorsMakeOdometryDriftAndAreOffByDefault) {
  const RobotModel model = docent();
  const auto straight = [](double t) { return Twist2{0.3 * ramp(t), 0.0, 0.0}; };
  World clean(model, quiet(false));
  const RunResult a = drive(clean, model, 10.0, straight);
  EXPECT_NEAR(a.truth.y_m, 0.0, 1e-12);
  SimOptions options = quiet(false);
  options.nonsystematic.wheel_slip_std = 0.02;
  options.nonsystematic.lateral_scrub_std = 0.02;
  World slippery(model, options);
  const RunResult b = drive(slippery, model, 10.0, straight);
  EXPECT_GT(std::hypot(b.odometry.x_m - b.truth.x_m, b.odometry.y_m - b.truth.y_m), 0.005);
}

TEST(World, RejectsInvalidCommandsWithoutMoving) {
  World world(swpc4(), quiet());
  ActuatorCommand bad;
  bad.module_count = 4;
  bad.wheel_rate_radps[2] = std::nan("");
  EXPECT_EQ(world.step(0.01, bad), Status::kError);
  EXPECT_STREQ(world.last_error(), "sim: non-finite actuator setpoint");
  ActuatorCommand wrong_count;
  wrong_count.module_count = 2;
  EXPECT_EQ(world.step(0.01, wrong_count), Status::kError);
  ActuatorCommand ok;
  ok.module_count = 4;
  EXPECT_EQ(world.step(-0.01, ok), Status::kError);
  EXPECT_EQ(world.time_s(), 0.0);
}

TEST(World, InvalidEffectsAreRejectedAtConstruction) {
  RobotModel model = docent();
  model.effects["caster_offset"]["module_1_scale"] = 1.1;
  EXPECT_THROW(World(model, SimOptions{}), std::invalid_argument);
}

}  // namespace
}  // namespace swivel::sim

namespace swivel::sim {
namespace {

using test::swpc4;

TEST(OpenLoop, SteeringRatesAreClampedToTheRobotsLimit) {
  RobotModel model = swpc4();
  HardwareState measured;
  measured.module_count = 4;  // every caster at 0 rad: a sideways twist turns them fast
  const Twist2 sideways{0.0, 0.5, 0.0};
  ActuatorCommand free;
  OpenLoopController(model).velocity(sideways, measured, free);
  EXPECT_GT(std::abs(free.steer_rate_radps[0]), 20.0);
  model.limits.steering_rate_radps = 6.0;
  ActuatorCommand limited;
  OpenLoopController(model).velocity(sideways, measured, limited);
  MotionLimits other;
  other.steering_rate_radps = 2.0;
  ActuatorCommand slower;
  OpenLoopController(model, other).velocity(sideways, measured, slower);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(std::abs(limited.steer_rate_radps[i]),
              std::min(6.0, std::abs(free.steer_rate_radps[i])));
    EXPECT_EQ(std::abs(slower.steer_rate_radps[i]),
              std::min(2.0, std::abs(free.steer_rate_radps[i])));
    EXPECT_EQ(limited.wheel_rate_radps[i], free.wheel_rate_radps[i]);
  }
}

}  // namespace
}  // namespace swivel::sim

namespace swivel::sim {
namespace {

// Turning a module's steering moves its angle now and as the latency reads it (the history
// turns with it), and leaves the other modules alone.
TEST(World, TurningTheSteeringMovesItNowAndInTheLateView) {
  RobotModel model = swpc4();
  model.effects["sensor_latency"]["delay_s"] = 0.02;
  SimOptions options = quiet(false);
  options.move_body = false;
  World world(model, options);
  const OpenLoopController controller(model);
  HardwareState hw;
  ActuatorCommand command;
  for (int k = 0; k < 20; ++k) {
    world.read(hw);
    controller.velocity(Twist2{0.2, 0.0, 0.4}, hw, command);
    world.step(0.01, command);
  }
  const double true_before = world.true_steer_rad(1);
  const double sensed_before = world.sensed_steer_rad(1);
  const double other = world.sensed_steer_rad(2);
  world.turn_steering(1, 0.3);
  EXPECT_DOUBLE_EQ(world.true_steer_rad(1), true_before + 0.3);
  EXPECT_NEAR(world.sensed_steer_rad(1), sensed_before + 0.3, 1e-12);
  EXPECT_DOUBLE_EQ(world.sensed_steer_rad(2), other);
  world.turn_steering(7, 0.3);  // no such module: nothing happens
  world.turn_steering(1, std::nan(""));
  EXPECT_DOUBLE_EQ(world.true_steer_rad(1), true_before + 0.3);
}

}  // namespace
}  // namespace swivel::sim
