// SPDX-License-Identifier: Apache-2.0
#include "swpc_drivetrain.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/plugin/abi.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"

namespace swivel::plugins {
namespace {

bool finite(double v) noexcept { return std::isfinite(v); }

// "swpc: module <i> <what>" for every module index, built at compile time so that forward()
// can name the module with a static text.
using ModuleText = std::array<char, 64>;
constexpr std::array<ModuleText, kMaxModules> module_texts(std::string_view what) {
  std::array<ModuleText, kMaxModules> out{};
  for (std::size_t m = 0; m < kMaxModules; ++m) {
    std::size_t n = 0;
    for (const char c : std::string_view("swpc: module ")) out[m][n++] = c;
    if (m >= 10) out[m][n++] = static_cast<char>('0' + m / 10);
    out[m][n++] = static_cast<char>('0' + m % 10);
    for (const char c : what) out[m][n++] = c;
  }
  return out;
}
constexpr auto kWheelImplausible = module_texts(" wheel rate implausible (encoder jump)");
constexpr auto kSteerImplausible = module_texts(" steering rate implausible (encoder jump)");

// Measured angles may be wrapped by the encoder; a step never turns more than half a turn.
double wrap_pi(double angle_rad) noexcept {
  return std::remainder(angle_rad, 2.0 * std::numbers::pi);
}

// 0 at or below half the threshold, 1 at or above it, C1-smooth in between.
double near_zero_gain(double speed_mps, double min_speed_mps) noexcept {
  if (!(min_speed_mps > 0.0)) {
    return 1.0;
  }
  const double s = (speed_mps - 0.5 * min_speed_mps) / (0.5 * min_speed_mps);
  if (s <= 0.0) {
    return 0.0;
  }
  if (s >= 1.0) {
    return 1.0;
  }
  return s * s * (3.0 - 2.0 * s);
}

}  // namespace

void SwpcDrivetrain::configure(const PluginContext& ctx) {
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  SwpcDrivetrainLimits limits;
  limits.max_wheel_rate_radps =
      params.number_or("max_wheel_rate_radps", limits.max_wheel_rate_radps, 1e-3, 1e5);
  limits.max_steer_rate_radps =
      params.number_or("max_steer_rate_radps", limits.max_steer_rate_radps, 1e-3, 1e5);
  limits.min_speed_mps = params.number_or("min_speed_mps", limits.min_speed_mps, 0.0, 1.0);
  limits.plausible_rate_factor =
      params.number_or("plausible_rate_factor", limits.plausible_rate_factor, 1.0, 1e3);
  params.finish();

  if (ctx.robot == nullptr) {
    throw ConfigError("swpc drivetrain: no robot model");
  }
  if (ctx.robot->drivetrain != DrivetrainKind::kSwpc) {
    throw ConfigError(ctx.robot->source_file + ": drivetrain: expected 'swpc' for the swpc plugin");
  }
  if (ctx.robot->limits.steering_rate_radps) {
    limits.commanded_steer_rate_radps = *ctx.robot->limits.steering_rate_radps;
  }
  const double counts = std::min(ctx.robot->sensors.wheel_encoder_counts_per_rev,
                                 ctx.robot->sensors.steering_encoder_counts_per_rev);
  if (counts > 0) limits.plausibility_margin_rad = 4.0 * 2.0 * std::numbers::pi / counts;
  try {
    configure(ctx.robot->modules, limits);
  } catch (const ConfigError& e) {
    throw ConfigError(ctx.robot->source_file + ": " + e.what());
  }
}

void SwpcDrivetrain::configure(std::span<const SwpcModuleParams> modules,
                               const SwpcDrivetrainLimits& limits) {
  if (modules.size() < 2 || modules.size() > kMaxModules) {
    throw ConfigError("swpc.modules: expected 2 to " + std::to_string(kMaxModules) +
                      " modules, got " + std::to_string(modules.size()));
  }
  for (std::size_t i = 0; i < modules.size(); ++i) {
    const SwpcModuleParams& m = modules[i];
    const std::string where = "swpc.modules[" + std::to_string(i) + "]";
    if (!finite(m.x_m) || !finite(m.y_m) || !finite(m.steering_offset_rad)) {
      throw ConfigError(where + ": expected finite x_m, y_m and steering_offset_rad");
    }
    // The inverse kinematics divides by d (lateral term) and r (rolling term).
    if (!(m.caster_offset_m > 0.0) || !finite(m.caster_offset_m)) {
      throw ConfigError(where + ".caster_offset_m: expected a positive number");
    }
    if (!(m.wheel_radius_m > 0.0) || !finite(m.wheel_radius_m)) {
      throw ConfigError(where + ".wheel_radius_m: expected a positive number");
    }
  }
  if (!(limits.max_wheel_rate_radps > 0.0) || !(limits.max_steer_rate_radps > 0.0) ||
      !(limits.min_speed_mps >= 0.0) || !finite(limits.max_wheel_rate_radps) ||
      !finite(limits.max_steer_rate_radps) || !finite(limits.min_speed_mps)) {
    throw ConfigError("swpc limits: expected positive rate limits and min_speed_mps >= 0");
  }
  if (!(limits.commanded_steer_rate_radps > 0.0)) {
    throw ConfigError("limits.steering_rate_radps: expected a positive number");
  }
  if (!finite(limits.plausible_rate_factor) || !(limits.plausible_rate_factor >= 1.0) ||
      !finite(limits.plausibility_margin_rad) || !(limits.plausibility_margin_rad >= 0.0)) {
    throw ConfigError(
        "swpc limits: expected plausible_rate_factor >= 1 and plausibility_margin_rad >= 0");
  }
  count_ = static_cast<std::uint32_t>(modules.size());
  for (std::size_t i = 0; i < modules.size(); ++i) {
    modules_[i] = modules[i];
  }
  limits_ = limits;
  states_ = {};
}

Status SwpcDrivetrain::forward(const HardwareState& previous, const HardwareState& current,
                               OdometryIncrement& out) noexcept {
  out = OdometryIncrement{};
  if (count_ == 0) {
    return fail("swpc: not configured");
  }
  if (previous.module_count != count_ || current.module_count != count_) {
    return fail("swpc: module count of the hardware state does not match the robot model");
  }
  const double dt_s = current.stamp_s - previous.stamp_s;
  if (!finite(dt_s)) {
    return fail("swpc: non-finite timestamp");
  }
  if (!(dt_s > 0.0)) {
    return fail("swpc: timestamps not increasing");
  }

  std::array<double, kMaxModules> phi{};
  std::array<double, kMaxModules> steer_rate{};
  std::array<double, kMaxModules> wheel_rate{};
  for (std::uint32_t i = 0; i < count_; ++i) {
    if (!finite(previous.steer_angle_rad[i]) || !finite(current.steer_angle_rad[i]) ||
        !finite(previous.wheel_angle_rad[i]) || !finite(current.wheel_angle_rad[i])) {
      return fail("swpc: non-finite steering or wheel angle");
    }
    const double dphi = wrap_pi(current.steer_angle_rad[i] - previous.steer_angle_rad[i]);
    const double dpsi = current.wheel_angle_rad[i] - previous.wheel_angle_rad[i];
    states_[i].wheel_rate_meas_radps = dpsi / dt_s;
    // An encoder jump (lost counts, a glitch) must not reach the odometry.
    if (std::abs(dpsi) > limits_.plausible_rate_factor * limits_.max_wheel_rate_radps * dt_s +
                             limits_.plausibility_margin_rad) {
      return fail(kWheelImplausible[i].data());
    }
    if (std::abs(dphi) > limits_.plausible_rate_factor * limits_.max_steer_rate_radps * dt_s +
                             limits_.plausibility_margin_rad) {
      return fail(kSteerImplausible[i].data());
    }
    // The rates are means over the step; the mid-step angle makes the fit second-order.
    phi[i] = previous.steer_angle_rad[i] + 0.5 * dphi + modules_[i].steering_offset_rad;
    steer_rate[i] = dphi / dt_s;
    wheel_rate[i] = dpsi / dt_s;
  }

  const std::span<const double> phi_span(phi.data(), count_);
  const swpc::ForwardResult fit =
      swpc::forward(std::span<const SwpcModuleParams>(modules_.data(), count_), phi_span,
                    std::span<const double>(steer_rate.data(), count_),
                    std::span<const double>(wheel_rate.data(), count_));
  if (!fit.ok) {
    return fail("swpc: forward kinematics degenerate (module geometry or angles)");
  }

  for (std::uint32_t i = 0; i < count_; ++i) {
    states_[i].steer_angle_rad = current.steer_angle_rad[i];
    states_[i].wheel_rate_meas_radps = wheel_rate[i];
  }
  out.dt_s = dt_s;
  out.twist = fit.twist;
  out.delta = swpc::integrate_twist(fit.twist, dt_s);
  out.residual = fit.residual;
  out.valid = true;
  return Status::kOk;
}

Status SwpcDrivetrain::inverse(const Twist2& command, const HardwareState& current, double dt_s,
                               ActuatorCommand& out, Twist2& applied) noexcept {
  // Safe defaults first: whatever fails below, the actuators get zero rates.
  out = ActuatorCommand{};
  out.module_count = count_;
  applied = Twist2{};
  for (std::uint32_t i = 0; i < count_; ++i) {
    states_[i].steer_rate_cmd_radps = 0.0;
    states_[i].wheel_rate_cmd_radps = 0.0;
  }
  if (count_ == 0) {
    return fail("swpc: not configured");
  }
  if (!finite(command.vx_mps) || !finite(command.vy_mps) || !finite(command.wz_radps)) {
    return fail("swpc: non-finite velocity command");
  }
  if (!finite(dt_s) || dt_s < 0.0) {
    return fail("swpc: invalid cycle period");
  }
  if (current.module_count != count_) {
    return fail("swpc: module count of the hardware state does not match the robot model");
  }
  std::array<double, kMaxModules> phi{};
  for (std::uint32_t i = 0; i < count_; ++i) {
    if (!finite(current.steer_angle_rad[i])) {
      return fail("swpc: non-finite steering angle");
    }
    phi[i] = current.steer_angle_rad[i] + modules_[i].steering_offset_rad;
    states_[i].steer_angle_rad = current.steer_angle_rad[i];
  }
  const std::span<const SwpcModuleParams> modules(modules_.data(), count_);

  // Both rates are linear in the twist at fixed phi: evaluate the inverse kinematics once,
  // then one factor keeps the direction and brings the most loaded actuator exactly to its
  // limit.
  std::array<swpc::ModuleRates, kMaxModules> rates{};
  for (std::uint32_t i = 0; i < count_; ++i) {
    rates[i] = swpc::inverse_module(modules_[i], phi[i], command);
  }
  const double scale = swpc::desaturation_scale(
      std::span<const swpc::ModuleRates>(rates.data(), count_), limits_.max_wheel_rate_radps,
      std::min(limits_.max_steer_rate_radps, limits_.commanded_steer_rate_radps));

  // Near zero speed. At a fixed steering angle the lateral part of v_s can only be produced
  // by swinging the caster: phi_dot = (n . v_s)/d - w, i.e. 1/d = 50 rad per metre of
  // lateral travel for d = 20 mm, against 1/r = 18 rad per metre for the wheel. A command
  // that hovers around zero (joystick noise, a controller settling) would therefore make
  // the casters wander through large angles while the robot barely moves, and a caster
  // left at an arbitrary angle then needs large steering rates when motion resumes. Below
  // min_speed the whole twist is faded smoothly to exactly zero, so the casters hold their
  // angle; fading the twist rather than only the steering rate keeps every module
  // consistent (no lateral scrub) and `applied` truthful.
  const Twist2 limited{command.vx_mps * scale, command.vy_mps * scale, command.wz_radps * scale};
  const double factor = scale * near_zero_gain(swpc::max_steering_axis_speed(modules, limited),
                                               limits_.min_speed_mps);
  const Twist2 twist{command.vx_mps * factor, command.vy_mps * factor, command.wz_radps * factor};

  for (std::uint32_t i = 0; i < count_; ++i) {
    out.wheel_rate_radps[i] = rates[i].wheel_rate_radps * factor;
    out.steer_rate_radps[i] = rates[i].steer_rate_radps * factor;
    out.mode[i] = ModuleDriveMode::kVelocity;
    states_[i].wheel_rate_cmd_radps = out.wheel_rate_radps[i];
    states_[i].steer_rate_cmd_radps = out.steer_rate_radps[i];
  }
  applied = twist;
  return Status::kOk;
}

void SwpcDrivetrain::module_states(std::span<ModuleState> out) const noexcept {
  const std::size_t n = out.size() < count_ ? out.size() : count_;
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = states_[i];
  }
}

}  // namespace swivel::plugins

SWIVEL_EXPORT_PLUGIN(swivel::plugins::SwpcDrivetrain, swivel::Drivetrain, "swpc")
