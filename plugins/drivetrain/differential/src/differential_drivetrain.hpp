// SPDX-License-Identifier: Apache-2.0
#pragma once
// The `differential` drivetrain plugin: a thin adapter between the loop's HardwareState /
// ActuatorCommand and swivel/differential/differential_kinematics.hpp. Module 0 is the left
// wheel, module 1 the right one. The robot is non-holonomic: vy commands are ignored.
//
// Plausibility: a wheel angle increment that implies a rate above plausible_rate_factor x
// max_wheel_rate_radps (plus plausibility_margin_rad, for quantization over a short step)
// cannot come from the wheel: forward() rejects the reading with kError naming the wheel,
// and the module state keeps the implausible measured rate for diagnostics.

#include <array>
#include <cstdint>
#include <span>

#include "swivel/plugin/drivetrain.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::plugins {

class DifferentialDrivetrain final : public Drivetrain {
 public:
  static constexpr double kDefaultMaxWheelRateRadps = 20.0;
  static constexpr double kDefaultPlausibleRateFactor = 3.0;
  /// Angle allowance of the plausibility check when no encoder resolution is known, rad.
  static constexpr double kDefaultPlausibilityMarginRad = 0.01;

  /// Off the loop. Geometry from ctx.robot->differential; params max_wheel_rate_radps
  /// (optional, default 20) and plausible_rate_factor (optional, default 3); the
  /// plausibility margin is 4 counts of sensors.wheel_encoder_counts_per_rev.
  /// @throws ConfigError naming the key.
  void configure(const PluginContext& ctx) override;

  /// Configures from plain values (tests, tools). @throws ConfigError.
  void configure(const DifferentialParams& geometry, double max_wheel_rate_radps,
                 double plausible_rate_factor = kDefaultPlausibleRateFactor,
                 double plausibility_margin_rad = kDefaultPlausibilityMarginRad);

  [[nodiscard]] std::uint32_t module_count() const noexcept override { return 2; }

  /// Real-time safe. Exact arc from the wheel angle increments; twist = increment / dt.
  /// kError ("differential: left wheel rate implausible ...") for an implausible increment.
  Status forward(const HardwareState& previous, const HardwareState& current,
                 OdometryIncrement& out) noexcept override;

  /// Real-time safe. Wheel rates for (vx, wz), both scaled by one factor so that no wheel
  /// exceeds the limit (the path curvature is kept); vy is dropped.
  Status inverse(const Twist2& command, const HardwareState& current, double dt_s,
                 ActuatorCommand& out, Twist2& applied) noexcept override;

  /// Real-time safe.
  void module_states(std::span<ModuleState> out) const noexcept override;

  /// Real-time safe. Static message for the last kError.
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

  [[nodiscard]] double max_wheel_rate_radps() const noexcept { return max_wheel_rate_radps_; }
  /// Above this |wheel rate| a reading is rejected, rad/s (before the margin).
  [[nodiscard]] double plausible_wheel_rate_radps() const noexcept {
    return plausible_rate_factor_ * max_wheel_rate_radps_;
  }

 private:
  Status fail(const char* message) noexcept {
    last_error_ = message;
    return Status::kError;
  }

  DifferentialParams geometry_{};
  double max_wheel_rate_radps_ = kDefaultMaxWheelRateRadps;
  double plausible_rate_factor_ = kDefaultPlausibleRateFactor;
  double plausibility_margin_rad_ = kDefaultPlausibilityMarginRad;
  bool configured_ = false;
  std::array<ModuleState, 2> states_{};
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
