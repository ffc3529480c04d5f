// SPDX-License-Identifier: Apache-2.0
#include "swpc_drivetrain.hpp"

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "alloc_guard.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"

namespace swivel::plugins {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDt = 0.001;  // 1 kHz loop

std::vector<SwpcModuleParams> design_modules() {
  return {{0.215, 0.125, 0.0, 0.020, 0.055},
          {0.215, -0.125, 0.0, 0.020, 0.055},
          {-0.215, -0.125, 0.0, 0.020, 0.055},
          {-0.215, 0.125, 0.0, 0.020, 0.055}};
}

// The design robot with homing errors of a few tenths of a radian.
std::vector<SwpcModuleParams> offset_modules() {
  auto modules = design_modules();
  const std::array<double, 4> offsets{0.3, -0.2, 0.45, -0.35};
  for (std::size_t i = 0; i < 4; ++i) modules[i].steering_offset_rad = offsets[i];
  return modules;
}

double wrap(double a) { return std::remainder(a, 2.0 * kPi); }

// A caster robot moving with a prescribed body twist: the casters follow the no-slip law
// phi_dot = (n . v_s)/d - w, the wheels roll r psi_dot = u . v_s (RK4, 10 substeps per
// cycle). Readings follow the hardware convention measured = true - offset, wrapped.
class CasterRobot {
 public:
  CasterRobot(std::vector<SwpcModuleParams> modules, std::vector<double> phi_true)
      : modules_(std::move(modules)), phi_(std::move(phi_true)), psi_(modules_.size(), 0.0) {}

  void advance(const Twist2& t, double dt_s) {
    const int substeps = 10;
    const double h = dt_s / substeps;
    const std::size_t n = modules_.size();
    for (int k = 0; k < substeps; ++k) {
      // State: phi_i, psi_i per module, then the pose (x, y, yaw).
      std::vector<double> y(2 * n + 3);
      for (std::size_t i = 0; i < n; ++i) {
        y[2 * i] = phi_[i];
        y[2 * i + 1] = psi_[i];
      }
      y[2 * n] = pose_.x_m;
      y[2 * n + 1] = pose_.y_m;
      y[2 * n + 2] = pose_.yaw_rad;
      auto f = [&](const std::vector<double>& s) {
        std::vector<double> d(s.size());
        for (std::size_t i = 0; i < n; ++i) {
          const SwpcModuleParams& m = modules_[i];
          const double vsx = t.vx_mps - t.wz_radps * m.y_m;
          const double vsy = t.vy_mps + t.wz_radps * m.x_m;
          const double c = std::cos(s[2 * i]);
          const double sn = std::sin(s[2 * i]);
          d[2 * i] = (-sn * vsx + c * vsy) / m.caster_offset_m - t.wz_radps;
          d[2 * i + 1] = (c * vsx + sn * vsy) / m.wheel_radius_m;
        }
        const double yaw = s[2 * n + 2];
        d[2 * n] = std::cos(yaw) * t.vx_mps - std::sin(yaw) * t.vy_mps;
        d[2 * n + 1] = std::sin(yaw) * t.vx_mps + std::cos(yaw) * t.vy_mps;
        d[2 * n + 2] = t.wz_radps;
        return d;
      };
      auto axpy = [](const std::vector<double>& a, double s, const std::vector<double>& b) {
        std::vector<double> r(a.size());
        for (std::size_t j = 0; j < a.size(); ++j) r[j] = a[j] + s * b[j];
        return r;
      };
      const auto k1 = f(y);
      const auto k2 = f(axpy(y, h / 2, k1));
      const auto k3 = f(axpy(y, h / 2, k2));
      const auto k4 = f(axpy(y, h, k3));
      for (std::size_t j = 0; j < y.size(); ++j) {
        y[j] += h / 6 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
      }
      for (std::size_t i = 0; i < n; ++i) {
        phi_[i] = y[2 * i];
        psi_[i] = y[2 * i + 1];
      }
      pose_ = {y[2 * n], y[2 * n + 1], y[2 * n + 2]};
    }
    stamp_s_ += dt_s;
  }

  [[nodiscard]] HardwareState read() const {
    HardwareState s;
    s.stamp_s = stamp_s_;
    s.module_count = static_cast<std::uint32_t>(modules_.size());
    for (std::size_t i = 0; i < modules_.size(); ++i) {
      s.steer_angle_rad[i] = wrap(phi_[i] - modules_[i].steering_offset_rad);
      s.wheel_angle_rad[i] = psi_[i];
    }
    return s;
  }

  [[nodiscard]] const Pose2& pose() const { return pose_; }

 private:
  std::vector<SwpcModuleParams> modules_;
  std::vector<double> phi_;
  std::vector<double> psi_;
  Pose2 pose_;
  double stamp_s_ = 10.0;
};

Pose2 compose(const Pose2& a, const Pose2& delta) {
  const double c = std::cos(a.yaw_rad);
  const double s = std::sin(a.yaw_rad);
  return {a.x_m + c * delta.x_m - s * delta.y_m, a.y_m + s * delta.x_m + c * delta.y_m,
          a.yaw_rad + delta.yaw_rad};
}

struct OdometryRun {
  Pose2 pose;
  double max_twist_error = 0.0;
  double max_residual = 0.0;
  bool all_ok = true;
};

// Drives `robot` through `steps` cycles of twist `t`, odometry from `drivetrain`.
OdometryRun run_odometry(SwpcDrivetrain& drivetrain, CasterRobot& robot, const Twist2& t,
                         int steps) {
  OdometryRun run;
  HardwareState previous = robot.read();
  for (int k = 0; k < steps; ++k) {
    robot.advance(t, kDt);
    const HardwareState current = robot.read();
    OdometryIncrement inc;
    run.all_ok = run.all_ok && drivetrain.forward(previous, current, inc) == Status::kOk &&
                 inc.valid && inc.dt_s == current.stamp_s - previous.stamp_s;
    run.pose = compose(run.pose, inc.delta);
    run.max_twist_error = std::max({run.max_twist_error, std::abs(inc.twist.vx_mps - t.vx_mps),
                                    std::abs(inc.twist.vy_mps - t.vy_mps),
                                    std::abs(inc.twist.wz_radps - t.wz_radps)});
    run.max_residual = std::max(run.max_residual, inc.residual);
    previous = current;
  }
  return run;
}

SwpcDrivetrain configured(const std::vector<SwpcModuleParams>& modules,
                          const SwpcDrivetrainLimits& limits = {}) {
  SwpcDrivetrain drivetrain;
  drivetrain.configure(modules, limits);
  return drivetrain;
}

HardwareState state_at(const std::vector<double>& measured_steer) {
  HardwareState s;
  s.module_count = static_cast<std::uint32_t>(measured_steer.size());
  for (std::size_t i = 0; i < measured_steer.size(); ++i) s.steer_angle_rad[i] = measured_steer[i];
  return s;
}

TEST(SwpcDrivetrain, OdometryFollowsAKnownTwistWithSteeringOffsets) {
  // Casters start far from alignment so they swing through large angles while driving.
  const std::vector<double> phi0{1.0, -2.0, 2.8, 0.2};
  const std::vector<Twist2> twists{{0.3, 0.1, 0.0}, {0.0, -0.25, 0.8}, {-0.2, 0.15, -1.5}};
  for (const Twist2& t : twists) {
    CasterRobot robot(offset_modules(), phi0);
    SwpcDrivetrain drivetrain = configured(offset_modules());

    const OdometryRun run = run_odometry(drivetrain, robot, t, 2000);

    ASSERT_TRUE(run.all_ok);
    // Mid-step angles make each step second-order accurate: the mean of u over a step
    // differs from u(mid) by about (dt phi_dot)^2 / 24; phi_dot reaches ~20 rad/s here, so
    // ~2e-5 m/s per step. A first-order (start-angle) fit would be off by ~1e-3.
    EXPECT_LT(run.max_twist_error, 5e-5);
    EXPECT_LT(run.max_residual, 5e-5);
    EXPECT_NEAR(run.pose.x_m, robot.pose().x_m, 1e-5);
    EXPECT_NEAR(run.pose.y_m, robot.pose().y_m, 1e-5);
    EXPECT_NEAR(run.pose.yaw_rad, robot.pose().yaw_rad, 1e-5);
  }
}

TEST(SwpcDrivetrain, WrongOffsetSignGivesWrongOdometryAndResidual) {
  // Guards the convention true = measured + offset: flipping the sign must be visible.
  auto flipped = offset_modules();
  for (auto& m : flipped) m.steering_offset_rad = -m.steering_offset_rad;
  CasterRobot robot(offset_modules(), {1.0, -2.0, 2.8, 0.2});
  SwpcDrivetrain drivetrain = configured(flipped);

  const OdometryRun run = run_odometry(drivetrain, robot, {0.3, 0.1, 0.4}, 500);

  EXPECT_GT(run.max_twist_error, 1e-2);
  EXPECT_GT(run.max_residual, 1e-3);
}

TEST(SwpcDrivetrain, ForwardReportsMeasuredWheelRatesAndHandlesWrappedSteering) {
  SwpcDrivetrain drivetrain = configured(design_modules());
  // Every caster crosses the +-pi seam during the step.
  CasterRobot robot(design_modules(), {kPi - 1e-4, -kPi + 1e-4, kPi - 2e-4, kPi});
  const OdometryRun run = run_odometry(drivetrain, robot, {0.0, 0.3, 0.0}, 200);
  ASSERT_TRUE(run.all_ok);
  EXPECT_LT(run.max_twist_error, 1e-5);

  std::array<ModuleState, 4> states{};
  drivetrain.module_states(states);
  const HardwareState last = robot.read();
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(states[i].steer_angle_rad, last.steer_angle_rad[i]);
    // Translation along +y with trailing casters: each wheel rolls at |v|/r forwards or
    // backwards depending on its (unaligned) heading.
    EXPECT_LE(std::abs(states[i].wheel_rate_meas_radps), 0.3 / 0.055 + 1e-6);
  }
}

TEST(SwpcDrivetrain, InverseCommandsReproduceTheTwistThroughForwardKinematics) {
  // Closed loop over the convention: inverse() at measured angles, the casters execute the
  // commanded rates, forward() on the resulting readings must see the applied twist.
  const auto modules = offset_modules();
  SwpcDrivetrain drivetrain = configured(modules);
  std::array<double, 4> phi_true{0.4, 2.0, -1.1, -2.9};
  std::array<double, 4> psi{};
  const Twist2 command{0.25, -0.1, 0.6};
  double max_error = 0.0;
  double max_residual = 0.0;
  auto read = [&](double stamp) {
    HardwareState s;
    s.stamp_s = stamp;
    s.module_count = 4;
    for (std::size_t i = 0; i < 4; ++i) {
      s.steer_angle_rad[i] = phi_true[i] - modules[i].steering_offset_rad;
      s.wheel_angle_rad[i] = psi[i];
    }
    return s;
  };
  HardwareState previous = read(0.0);
  for (int k = 1; k <= 1000; ++k) {
    ActuatorCommand cmd;
    Twist2 applied;
    ASSERT_EQ(drivetrain.inverse(command, previous, kDt, cmd, applied), Status::kOk);
    ASSERT_EQ(cmd.module_count, 4U);
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_EQ(cmd.mode[i], ModuleDriveMode::kVelocity);
      phi_true[i] += cmd.steer_rate_radps[i] * kDt;
      psi[i] += cmd.wheel_rate_radps[i] * kDt;
    }
    const HardwareState current = read(k * kDt);
    OdometryIncrement inc;
    ASSERT_EQ(drivetrain.forward(previous, current, inc), Status::kOk);
    max_error = std::max({max_error, std::abs(inc.twist.vx_mps - applied.vx_mps),
                          std::abs(inc.twist.vy_mps - applied.vy_mps),
                          std::abs(inc.twist.wz_radps - applied.wz_radps)});
    max_residual = std::max(max_residual, inc.residual);
    previous = current;
  }
  // Rates are held over a step while the angle moves by up to dt * phi_dot: first order.
  EXPECT_LT(max_error, 5e-3);
  EXPECT_LT(max_residual, 5e-3);
}

TEST(SwpcDrivetrain, DesaturationScalesTheWholeTwistToTheBindingLimit) {
  SwpcDrivetrainLimits limits;
  limits.max_wheel_rate_radps = 10.0;
  limits.max_steer_rate_radps = 4.0;
  SwpcDrivetrain drivetrain = configured(offset_modules(), limits);
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> v(-3.0, 3.0);
  for (int trial = 0; trial < 300; ++trial) {
    const HardwareState state = state_at({angle(rng), angle(rng), angle(rng), angle(rng)});
    const Twist2 command{v(rng), v(rng), 2 * v(rng)};
    ActuatorCommand cmd;
    Twist2 applied;

    ASSERT_EQ(drivetrain.inverse(command, state, kDt, cmd, applied), Status::kOk);

    const double scale = applied.vx_mps / command.vx_mps;
    EXPECT_GT(scale, 0.0);
    EXPECT_LE(scale, 1.0);
    EXPECT_NEAR(applied.vy_mps, scale * command.vy_mps, 1e-12);
    EXPECT_NEAR(applied.wz_radps, scale * command.wz_radps, 1e-12);
    double worst = 0.0;
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_LE(std::abs(cmd.wheel_rate_radps[i]), 10.0 * (1 + 1e-12));
      EXPECT_LE(std::abs(cmd.steer_rate_radps[i]), 4.0 * (1 + 1e-12));
      worst = std::max({worst, std::abs(cmd.wheel_rate_radps[i]) / 10.0,
                        std::abs(cmd.steer_rate_radps[i]) / 4.0});
    }
    if (scale < 1.0) {
      EXPECT_NEAR(worst, 1.0, 1e-12);
    }
  }
}

TEST(SwpcDrivetrain, SteeringRatesStayBoundedAndContinuousAsTheTwistPassesThroughZero) {
  SwpcDrivetrainLimits limits;
  limits.min_speed_mps = 0.01;
  SwpcDrivetrain drivetrain = configured(design_modules(), limits);
  const HardwareState state = state_at({0.0, kPi / 2, kPi, -kPi / 2});
  // A mostly-lateral command reversing through zero: the worst case for the d-term.
  const Twist2 direction{0.05, 0.3, 0.2};
  double previous_max_steer = 0.0;
  double max_jump = 0.0;
  int held = 0;
  for (int k = -1000; k <= 1000; ++k) {
    const double s = k / 1000.0;
    ActuatorCommand cmd;
    Twist2 applied;
    ASSERT_EQ(
        drivetrain.inverse({s * direction.vx_mps, s * direction.vy_mps, s * direction.wz_radps},
                           state, kDt, cmd, applied),
        Status::kOk);
    const double speed = swpc::max_steering_axis_speed(
        design_modules(), {s * direction.vx_mps, s * direction.vy_mps, s * direction.wz_radps});
    double max_steer = 0.0;
    for (std::size_t i = 0; i < 4; ++i) {
      max_steer = std::max(max_steer, std::abs(cmd.steer_rate_radps[i]));
      if (speed <= 0.5 * limits.min_speed_mps) {
        EXPECT_EQ(cmd.steer_rate_radps[i], 0.0);
        EXPECT_EQ(cmd.wheel_rate_radps[i], 0.0);
      }
    }
    if (speed <= 0.5 * limits.min_speed_mps) ++held;
    EXPECT_LE(max_steer, limits.max_steer_rate_radps * (1 + 1e-12));
    // Never more steering than the undamped inverse kinematics would ask for.
    EXPECT_LE(max_steer, speed / 0.020 + std::abs(s * direction.wz_radps) + 1e-12);
    if (k > -1000) max_jump = std::max(max_jump, std::abs(max_steer - previous_max_steer));
    previous_max_steer = max_steer;
  }
  EXPECT_GT(held, 0);
  // 2001 samples across +-15 rad/s: a continuous profile moves little per sample.
  EXPECT_LT(max_jump, 0.1);
}

TEST(SwpcDrivetrain, CommandNoiseBelowTheThresholdLeavesTheCastersStill) {
  SwpcDrivetrainLimits limits;
  limits.min_speed_mps = 0.01;
  SwpcDrivetrain drivetrain = configured(design_modules(), limits);
  const HardwareState state = state_at({0.3, 1.2, -2.0, 2.9});
  std::mt19937 rng(37);
  std::normal_distribution<double> noise(0.0, 0.0008);
  for (int k = 0; k < 1000; ++k) {
    const Twist2 command{noise(rng), noise(rng), noise(rng)};
    if (swpc::max_steering_axis_speed(design_modules(), command) > 0.005) continue;
    ActuatorCommand cmd;
    Twist2 applied;
    ASSERT_EQ(drivetrain.inverse(command, state, kDt, cmd, applied), Status::kOk);
    for (std::size_t i = 0; i < 4; ++i) {
      ASSERT_EQ(cmd.steer_rate_radps[i], 0.0);
      ASSERT_EQ(cmd.wheel_rate_radps[i], 0.0);
    }
    EXPECT_EQ(applied.vx_mps, 0.0);
  }
  // Above the threshold the command passes unchanged.
  ActuatorCommand cmd;
  Twist2 applied;
  ASSERT_EQ(drivetrain.inverse({0.02, 0.0, 0.0}, state, kDt, cmd, applied), Status::kOk);
  EXPECT_EQ(applied.vx_mps, 0.02);
}

TEST(SwpcDrivetrain, NonFiniteInputsFailWithAStaticMessageAndZeroRates) {
  SwpcDrivetrain drivetrain = configured(design_modules());
  HardwareState state = state_at({0.1, 0.2, 0.3, 0.4});
  ActuatorCommand cmd;
  Twist2 applied;
  const double nan = std::numeric_limits<double>::quiet_NaN();

  EXPECT_EQ(drivetrain.inverse({nan, 0.0, 0.0}, state, kDt, cmd, applied), Status::kError);
  EXPECT_STREQ(drivetrain.last_error(), "swpc: non-finite velocity command");
  EXPECT_EQ(cmd.module_count, 4U);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(cmd.wheel_rate_radps[i], 0.0);

  state.steer_angle_rad[2] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(drivetrain.inverse({0.1, 0.0, 0.0}, state, kDt, cmd, applied), Status::kError);
  EXPECT_STREQ(drivetrain.last_error(), "swpc: non-finite steering angle");
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(cmd.steer_rate_radps[i], 0.0);

  HardwareState previous = state_at({0.1, 0.2, 0.3, 0.4});
  HardwareState current = previous;
  current.stamp_s = kDt;
  current.wheel_angle_rad[1] = nan;
  OdometryIncrement inc;
  EXPECT_EQ(drivetrain.forward(previous, current, inc), Status::kError);
  EXPECT_STREQ(drivetrain.last_error(), "swpc: non-finite steering or wheel angle");
  EXPECT_FALSE(inc.valid);

  current.wheel_angle_rad[1] = 0.0;
  current.stamp_s = previous.stamp_s;
  EXPECT_EQ(drivetrain.forward(previous, current, inc), Status::kError);
  EXPECT_STREQ(drivetrain.last_error(), "swpc: timestamps not increasing");

  current.stamp_s = kDt;
  current.module_count = 3;
  EXPECT_EQ(drivetrain.forward(previous, current, inc), Status::kError);
  EXPECT_STREQ(drivetrain.last_error(),
               "swpc: module count of the hardware state does not match the robot model");
}

TEST(SwpcDrivetrain, ImplausibleIncrementsAreRejectedNamingTheModule) {
  // Limits 40 rad/s (wheel) and 12 rad/s (steering), factor 3, margin 0.01 rad: over 1 ms
  // a wheel may turn 0.13 rad and a caster 0.046 rad.
  SwpcDrivetrain drivetrain = configured(design_modules());
  const HardwareState previous = state_at({0.1, 0.2, 0.3, 0.4});
  HardwareState current = previous;
  current.stamp_s = kDt;
  OdometryIncrement inc;
  current.wheel_angle_rad[2] = 0.12;
  current.steer_angle_rad[1] = 0.2 + 0.04;
  EXPECT_EQ(drivetrain.forward(previous, current, inc), Status::kOk);

  current.wheel_angle_rad[2] = 0.14;
  EXPECT_EQ(drivetrain.forward(previous, current, inc), Status::kError);
  EXPECT_STREQ(drivetrain.last_error(), "swpc: module 2 wheel rate implausible (encoder jump)");
  EXPECT_FALSE(inc.valid);
  std::array<ModuleState, 4> states{};
  drivetrain.module_states(states);
  EXPECT_NEAR(states[2].wheel_rate_meas_radps, 140.0, 1e-9);

  current.wheel_angle_rad[2] = 0.0;
  current.steer_angle_rad[1] = 0.2 - 0.05;
  EXPECT_EQ(drivetrain.forward(previous, current, inc), Status::kError);
  EXPECT_STREQ(drivetrain.last_error(), "swpc: module 1 steering rate implausible (encoder jump)");
}

TEST(SwpcDrivetrain, ModuleStatesReportCommandedAndMeasuredValues) {
  SwpcDrivetrain drivetrain = configured(offset_modules());
  const HardwareState state = state_at({0.5, -0.5, 1.5, -1.5});
  ActuatorCommand cmd;
  Twist2 applied;
  ASSERT_EQ(drivetrain.inverse({0.1, 0.05, 0.2}, state, kDt, cmd, applied), Status::kOk);

  std::array<ModuleState, 4> states{};
  drivetrain.module_states(states);

  const auto modules = offset_modules();
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(states[i].steer_angle_rad, state.steer_angle_rad[i]);
    EXPECT_EQ(states[i].steer_rate_cmd_radps, cmd.steer_rate_radps[i]);
    EXPECT_EQ(states[i].wheel_rate_cmd_radps, cmd.wheel_rate_radps[i]);
    // The library sees the true angle = measured + offset.
    const auto expected = swpc::inverse_module(
        modules[i], state.steer_angle_rad[i] + modules[i].steering_offset_rad, applied);
    EXPECT_NEAR(cmd.steer_rate_radps[i], expected.steer_rate_radps, 1e-15);
    EXPECT_NEAR(cmd.wheel_rate_radps[i], expected.wheel_rate_radps, 1e-15);
  }
}

TEST(SwpcDrivetrain, LoopCallsDoNotAllocate) {
  std::vector<SwpcModuleParams> modules(kMaxModules);
  for (std::size_t i = 0; i < kMaxModules; ++i) {
    const double a = 2.0 * kPi * static_cast<double>(i) / kMaxModules;
    modules[i] = {0.4 * std::cos(a), 0.4 * std::sin(a), 0.1, 0.02, 0.05};
  }
  SwpcDrivetrain drivetrain = configured(modules);
  HardwareState previous;
  previous.module_count = kMaxModules;
  for (std::size_t i = 0; i < kMaxModules; ++i)
    previous.steer_angle_rad[i] = 0.1 * static_cast<double>(i);
  HardwareState current = previous;
  std::array<ModuleState, kMaxModules> states{};

  // Counts operator new everywhere and, outside sanitizer builds, malloc (Eigen's) too.
  test::AllocCounter guard;
  for (int k = 1; k <= 1000; ++k) {
    current.stamp_s = k * kDt;
    ActuatorCommand cmd;
    Twist2 applied;
    ASSERT_EQ(drivetrain.inverse({0.2, 0.1, 0.3}, previous, kDt, cmd, applied), Status::kOk);
    for (std::size_t i = 0; i < kMaxModules; ++i) {
      current.steer_angle_rad[i] += cmd.steer_rate_radps[i] * kDt;
      current.wheel_angle_rad[i] += cmd.wheel_rate_radps[i] * kDt;
    }
    OdometryIncrement inc;
    ASSERT_EQ(drivetrain.forward(previous, current, inc), Status::kOk);
    drivetrain.module_states(states);
    previous = current;
  }
  EXPECT_EQ(guard.counts().allocations, 0U);
}

TEST(SwpcDrivetrain, ConfigureRejectsBadGeometry) {
  SwpcDrivetrain drivetrain;
  std::vector<SwpcModuleParams> one(1);
  EXPECT_THROW(drivetrain.configure(one, {}), ConfigError);
  auto modules = design_modules();
  modules[2].caster_offset_m = 0.0;
  try {
    drivetrain.configure(modules, {});
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("swpc.modules[2].caster_offset_m"), std::string::npos)
        << e.what();
  }
  modules[2].caster_offset_m = 0.02;
  modules[0].wheel_radius_m = -0.05;
  EXPECT_THROW(drivetrain.configure(modules, {}), ConfigError);
  EXPECT_EQ(drivetrain.module_count(), 0U);
}

std::string source_path(const std::string& relative) {
  const char* dir = std::getenv("SWIVEL_SOURCE_DIR");
  return std::string(dir != nullptr ? dir : SWIVEL_SOURCE_DIR_FALLBACK) + "/" + relative;
}

TEST(SwpcDrivetrain, ConfiguresFromTheSwpc4ModelAndParams) {
  const RobotModel robot = load_robot_model(source_path("config/robots/swpc4.yaml"));
  ASSERT_EQ(robot.drivetrain, DrivetrainKind::kSwpc);
  ASSERT_EQ(robot.modules.size(), 4U);
  const auto design = design_modules();
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_DOUBLE_EQ(robot.modules[i].x_m, design[i].x_m);
    EXPECT_DOUBLE_EQ(robot.modules[i].y_m, design[i].y_m);
    EXPECT_DOUBLE_EQ(robot.modules[i].steering_offset_rad, 0.0);
    EXPECT_DOUBLE_EQ(robot.modules[i].caster_offset_m, 0.020);
    EXPECT_DOUBLE_EQ(robot.modules[i].wheel_radius_m, 0.055);
  }

  PluginContext ctx;
  ctx.robot = &robot;
  ctx.config_file = "swiveld.yaml";
  ctx.params_path = "drivetrain.params";
  ctx.params =
      YAML::Load("{max_wheel_rate_radps: 25.0, max_steer_rate_radps: 8.0, min_speed_mps: 0.002}");
  SwpcDrivetrain drivetrain;
  drivetrain.configure(ctx);
  EXPECT_EQ(drivetrain.module_count(), 4U);
  EXPECT_EQ(drivetrain.limits().max_wheel_rate_radps, 25.0);
  EXPECT_EQ(drivetrain.limits().max_steer_rate_radps, 8.0);
  EXPECT_EQ(drivetrain.limits().min_speed_mps, 0.002);

  ctx.params = YAML::Load("{max_wheel_rate: 25.0}");
  try {
    SwpcDrivetrain other;
    other.configure(ctx);
    FAIL() << "expected ConfigError for an unknown key";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("max_wheel_rate"), std::string::npos) << e.what();
  }
  ctx.params = YAML::Load("{max_steer_rate_radps: -1}");
  EXPECT_THROW(SwpcDrivetrain().configure(ctx), ConfigError);
}

// The robot model's limits: steering_rate_radps bounds every commanded steering rate (the
// whole twist scales, so the modules stay consistent); the plausibility check of measured
// increments keeps the plugin's own, higher max_steer_rate_radps.
TEST(SwpcDrivetrain, TheModelsSteeringRateLimitBoundsEverySteeringSetpoint) {
  RobotModel robot = load_robot_model(source_path("config/robots/swpc4.yaml"));
  robot.limits.steering_rate_radps = 2.0;
  PluginContext ctx;
  ctx.robot = &robot;
  ctx.config_file = "swiveld.yaml";
  ctx.params_path = "drivetrain.params";
  ctx.params = YAML::Load("{max_steer_rate_radps: 12.0}");
  SwpcDrivetrain drivetrain;
  drivetrain.configure(ctx);
  EXPECT_EQ(drivetrain.limits().commanded_steer_rate_radps, 2.0);
  EXPECT_EQ(drivetrain.limits().max_steer_rate_radps, 12.0);

  // Casters across the direction of travel: a sideways command swings them fast.
  const HardwareState state = state_at({0.0, 0.0, 0.0, 0.0});
  ActuatorCommand cmd;
  Twist2 applied;
  ASSERT_EQ(drivetrain.inverse(Twist2{0.0, 0.5, 0.0}, state, kDt, cmd, applied), Status::kOk);
  double fastest = 0.0;
  for (std::size_t i = 0; i < 4; ++i)
    fastest = std::max(fastest, std::abs(cmd.steer_rate_radps[i]));
  EXPECT_NEAR(fastest, 2.0, 1e-12);  // the most loaded steering motor at the model's limit
  EXPECT_GT(applied.vy_mps, 0.0);
  EXPECT_LT(applied.vy_mps, 0.5);

  // A measured swing at 6 rad/s (above 3 x 2 rad/s, below 3 x 12) is still plausible.
  HardwareState previous = state_at({0.0, 0.0, 0.0, 0.0});
  HardwareState current = state_at({0.006, 0.0, 0.0, 0.0});
  previous.stamp_s = 1.0;
  current.stamp_s = 1.0 + kDt;
  OdometryIncrement inc;
  EXPECT_EQ(drivetrain.forward(previous, current, inc), Status::kOk) << drivetrain.last_error();

  // Without the model's limit the plugin's own bound applies.
  robot.limits.steering_rate_radps.reset();
  SwpcDrivetrain unlimited;
  unlimited.configure(ctx);
  ASSERT_EQ(unlimited.inverse(Twist2{0.0, 0.5, 0.0}, state, kDt, cmd, applied), Status::kOk);
  fastest = 0.0;
  for (std::size_t i = 0; i < 4; ++i)
    fastest = std::max(fastest, std::abs(cmd.steer_rate_radps[i]));
  EXPECT_GT(fastest, 2.0);
}

TEST(SwpcDrivetrain, SharedLibraryExportsTheSwpcDrivetrain) {
  void* handle = dlopen(SWPC_PLUGIN_FILE, RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(handle, nullptr) << dlerror();
  auto entry = reinterpret_cast<SwivelPluginEntryPoint>(dlsym(handle, SWIVEL_PLUGIN_ENTRY_POINT));
  ASSERT_NE(entry, nullptr);
  const SwivelPluginDescriptor* descriptor = entry();
  EXPECT_EQ(descriptor->abi_version, SWIVEL_PLUGIN_ABI_VERSION);
  EXPECT_EQ(descriptor->kind, static_cast<std::uint32_t>(SWIVEL_PLUGIN_DRIVETRAIN));
  EXPECT_STREQ(descriptor->name, "swpc");
  const char* error = nullptr;
  void* instance = descriptor->create(&error);
  ASSERT_NE(instance, nullptr) << (error != nullptr ? error : "");
  EXPECT_EQ(static_cast<Drivetrain*>(instance)->module_count(), 0U);
  descriptor->destroy(instance);
  dlclose(handle);
}

}  // namespace
}  // namespace swivel::plugins
