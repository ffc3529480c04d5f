// SPDX-License-Identifier: Apache-2.0
#pragma once
// The `swpc` drivetrain plugin: a thin adapter between the loop's HardwareState /
// ActuatorCommand and the kinematics of swivel/swpc/swpc_kinematics.hpp. It converts the
// measured steering angles to true ones (true = measured + steering_offset).

#include <array>
#include <cstdint>
#include <limits>
#include <span>

#include "swivel/plugin/drivetrain.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::plugins {

/// Parameters read from the plugin's `params:` mapping.
struct SwpcDrivetrainLimits {
  double max_wheel_rate_radps = 40.0;  ///< |psi_dot| limit of every wheel
  double max_steer_rate_radps = 12.0;  ///< |phi_dot| limit of every steering motor
  /// The robot model's `limits: steering_rate_radps` (infinite when absent): what the
  /// robot's own controller lets a steering motor do. Commanded steering rates stay within
  /// it and max_steer_rate_radps; the encoder plausibility check keeps max_steer_rate_radps
  /// alone, so that a limit lowered here never rejects a faster measured swing.
  double commanded_steer_rate_radps = std::numeric_limits<double>::infinity();
  /// Below this fastest steering-axis speed a command is treated as "near zero": it is
  /// faded out, reaching exactly zero (casters hold their angle) at half of it. 0 disables.
  double min_speed_mps = 0.005;
  /// A reading whose increment implies a wheel or steering rate above this factor times its
  /// limit (plus plausibility_margin_rad) is rejected as an encoder jump.
  double plausible_rate_factor = 3.0;
  /// Angle allowance of that check (quantization over a short step), rad.
  double plausibility_margin_rad = 0.01;
};

class SwpcDrivetrain final : public Drivetrain {
 public:
  /// Off the loop. Geometry from ctx.robot->modules (2..kMaxModules, d > 0, r > 0) and the
  /// steering-rate limit from ctx.robot->limits; params max_wheel_rate_radps,
  /// max_steer_rate_radps, min_speed_mps, plausible_rate_factor (all optional); the
  /// plausibility margin is 4 counts of the coarser encoder of the model.
  /// @throws ConfigError naming the key.
  void configure(const PluginContext& ctx) override;

  /// Configures from plain values (tests, tools). @throws ConfigError.
  void configure(std::span<const SwpcModuleParams> modules, const SwpcDrivetrainLimits& limits);

  [[nodiscard]] std::uint32_t module_count() const noexcept override { return count_; }

  /// Real-time safe. Rates from angle increments over dt, true steering at mid-step,
  /// least-squares twist integrated exactly over dt; residual (m/s) into out.residual.
  /// kError ("swpc: module I wheel|steering rate implausible ...") for an increment beyond
  /// plausible_rate_factor x its limit; the module state keeps the measured wheel rate.
  Status forward(const HardwareState& previous, const HardwareState& current,
                 OdometryIncrement& out) noexcept override;

  /// Real-time safe. Rates at the current measured steering angles, the whole twist scaled
  /// so that every wheel rate is within max_wheel_rate_radps and every steering rate within
  /// max_steer_rate_radps and commanded_steer_rate_radps, faded to zero near zero speed.
  /// `dt_s` is only validated.
  Status inverse(const Twist2& command, const HardwareState& current, double dt_s,
                 ActuatorCommand& out, Twist2& applied) noexcept override;

  /// Real-time safe.
  void module_states(std::span<ModuleState> out) const noexcept override;

  /// Real-time safe. Static message for the last kError.
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

  [[nodiscard]] const SwpcDrivetrainLimits& limits() const noexcept { return limits_; }

 private:
  Status fail(const char* message) noexcept {
    last_error_ = message;
    return Status::kError;
  }

  std::array<SwpcModuleParams, kMaxModules> modules_{};
  std::uint32_t count_ = 0;
  SwpcDrivetrainLimits limits_;
  std::array<ModuleState, kMaxModules> states_{};
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
