#pragma once
// The `differential` drivetrain plugin: a thin adapter between the loop's HardwareState /
// ActuatorCommand and swivel/differential/differential_kinematics.hpp. Module 0 is the left
// wheel, module 1 the right one. The robot is non-holonomic: vy commands are ignored.

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

  /// Off the loop. Geometry from ctx.robot->differential; param max_wheel_rate_radps
  /// (optional, default 20). @throws ConfigError naming the key.
  void configure(const PluginContext& ctx) override;

  /// Configures from plain values (tests, tools). @throws ConfigError.
  void configure(const DifferentialParams& geometry, double max_wheel_rate_radps);

  [[nodiscard]] std::uint32_t module_count() const noexcept override { return 2; }

  /// Real-time safe. Exact arc from the wheel angle increments; twist = increment / dt.
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

 private:
  Status fail(const char* message) noexcept {
    last_error_ = message;
    return Status::kError;
  }

  DifferentialParams geometry_{};
  double max_wheel_rate_radps_ = kDefaultMaxWheelRateRadps;
  bool configured_ = false;
  std::array<ModuleState, 2> states_{};
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
