// SPDX-License-Identifier: Apache-2.0
#include "differential_drivetrain.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/differential/differential_kinematics.hpp"
#include "swivel/plugin/abi.hpp"

namespace swivel::plugins {
namespace {

bool positive_finite(double v) noexcept { return std::isfinite(v) && v > 0.0; }

}  // namespace

void DifferentialDrivetrain::configure(const PluginContext& ctx) {
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  const double max_rate_radps =
      params.number_or("max_wheel_rate_radps", kDefaultMaxWheelRateRadps, 1e-3, 1e5);
  const double plausible_factor =
      params.number_or("plausible_rate_factor", kDefaultPlausibleRateFactor, 1.0, 1e3);
  params.finish();

  if (ctx.robot == nullptr) throw ConfigError("differential drivetrain: no robot model");
  if (ctx.robot->drivetrain != DrivetrainKind::kDifferential) {
    throw ConfigError(ctx.robot->source_file +
                      ": drivetrain: expected 'differential' for the differential plugin");
  }
  const double counts = ctx.robot->sensors.wheel_encoder_counts_per_rev;
  const double margin_rad =
      counts > 0 ? 4.0 * 2.0 * std::numbers::pi / counts : kDefaultPlausibilityMarginRad;
  try {
    configure(ctx.robot->differential, max_rate_radps, plausible_factor, margin_rad);
  } catch (const ConfigError& e) {
    throw ConfigError(ctx.robot->source_file + ": " + e.what());
  }
}

void DifferentialDrivetrain::configure(const DifferentialParams& geometry,
                                       double max_wheel_rate_radps, double plausible_rate_factor,
                                       double plausibility_margin_rad) {
  if (!positive_finite(geometry.wheel_radius_left_m)) {
    throw ConfigError("differential.wheel_radius_left_m: expected a positive number");
  }
  if (!positive_finite(geometry.wheel_radius_right_m)) {
    throw ConfigError("differential.wheel_radius_right_m: expected a positive number");
  }
  if (!positive_finite(geometry.track_width_m)) {
    throw ConfigError("differential.track_width_m: expected a positive number");
  }
  if (!positive_finite(max_wheel_rate_radps)) {
    throw ConfigError("max_wheel_rate_radps: expected a positive number");
  }
  if (!std::isfinite(plausible_rate_factor) || !(plausible_rate_factor >= 1.0)) {
    throw ConfigError("plausible_rate_factor: expected a number >= 1");
  }
  if (!std::isfinite(plausibility_margin_rad) || !(plausibility_margin_rad >= 0.0)) {
    throw ConfigError("plausibility margin: expected a finite angle >= 0 rad");
  }
  geometry_ = geometry;
  max_wheel_rate_radps_ = max_wheel_rate_radps;
  plausible_rate_factor_ = plausible_rate_factor;
  plausibility_margin_rad_ = plausibility_margin_rad;
  states_ = {};
  configured_ = true;
}

Status DifferentialDrivetrain::forward(const HardwareState& previous, const HardwareState& current,
                                       OdometryIncrement& out) noexcept {
  out = OdometryIncrement{};
  if (!configured_) return fail("differential: not configured");
  if (previous.module_count < 2 || current.module_count < 2) {
    return fail("differential: hardware state has fewer than 2 wheels");
  }
  const double dt_s = current.stamp_s - previous.stamp_s;
  if (!std::isfinite(dt_s)) return fail("differential: non-finite timestamp");
  if (!(dt_s > 0.0)) return fail("differential: timestamps not increasing");
  const double dpsi_left_rad = current.wheel_angle_rad[0] - previous.wheel_angle_rad[0];
  const double dpsi_right_rad = current.wheel_angle_rad[1] - previous.wheel_angle_rad[1];
  if (!std::isfinite(dpsi_left_rad) || !std::isfinite(dpsi_right_rad)) {
    return fail("differential: non-finite wheel angle");
  }
  // An encoder jump (lost counts, a glitch) must not reach the odometry. The measured rates
  // stay in the module states so that the snapshot shows what was rejected.
  states_[0].wheel_rate_meas_radps = dpsi_left_rad / dt_s;
  states_[1].wheel_rate_meas_radps = dpsi_right_rad / dt_s;
  const double plausible_rad = plausible_wheel_rate_radps() * dt_s + plausibility_margin_rad_;
  if (std::abs(dpsi_left_rad) > plausible_rad) {
    return fail("differential: left wheel rate implausible (encoder jump)");
  }
  if (std::abs(dpsi_right_rad) > plausible_rad) {
    return fail("differential: right wheel rate implausible (encoder jump)");
  }

  const Pose2 delta = differential::forward_increment(geometry_, dpsi_left_rad, dpsi_right_rad);
  // The constant twist that moves the robot along exactly this arc in dt: forward speed is
  // the arc length (not the chord) over dt.
  const double arc_m = 0.5 * (geometry_.wheel_radius_left_m * dpsi_left_rad +
                              geometry_.wheel_radius_right_m * dpsi_right_rad);
  out.dt_s = dt_s;
  out.delta = delta;
  out.twist = Twist2{arc_m / dt_s, 0.0, delta.yaw_rad / dt_s};
  out.residual = 0.0;  // two wheels, two unknowns: no redundancy to measure slip with
  out.valid = true;
  return Status::kOk;
}

Status DifferentialDrivetrain::inverse(const Twist2& command, const HardwareState& /*current*/,
                                       double dt_s, ActuatorCommand& out,
                                       Twist2& applied) noexcept {
  // Safe defaults first: whatever fails below, the wheels get zero rates.
  out = ActuatorCommand{};
  out.module_count = 2;
  out.mode[0] = ModuleDriveMode::kVelocity;
  out.mode[1] = ModuleDriveMode::kVelocity;
  applied = Twist2{};
  states_[0].wheel_rate_cmd_radps = 0.0;
  states_[1].wheel_rate_cmd_radps = 0.0;
  if (!configured_) return fail("differential: not configured");
  if (!std::isfinite(command.vx_mps) || !std::isfinite(command.vy_mps) ||
      !std::isfinite(command.wz_radps)) {
    return fail("differential: non-finite velocity command");
  }
  if (!std::isfinite(dt_s) || dt_s < 0.0) return fail("differential: invalid cycle period");

  const double scale = differential::wheel_limit_scale(geometry_, command.vx_mps, command.wz_radps,
                                                       max_wheel_rate_radps_);
  applied = Twist2{command.vx_mps * scale, 0.0, command.wz_radps * scale};
  const differential::WheelRates rates =
      differential::inverse(geometry_, applied.vx_mps, applied.wz_radps);
  out.wheel_rate_radps[0] = rates.left_radps;
  out.wheel_rate_radps[1] = rates.right_radps;
  states_[0].wheel_rate_cmd_radps = rates.left_radps;
  states_[1].wheel_rate_cmd_radps = rates.right_radps;
  return Status::kOk;
}

void DifferentialDrivetrain::module_states(std::span<ModuleState> out) const noexcept {
  const std::size_t n = out.size() < states_.size() ? out.size() : states_.size();
  for (std::size_t i = 0; i < n; ++i) out[i] = states_[i];
}

}  // namespace swivel::plugins

SWIVEL_EXPORT_PLUGIN(swivel::plugins::DifferentialDrivetrain, swivel::Drivetrain, "differential")
