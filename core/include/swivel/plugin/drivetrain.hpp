// SPDX-License-Identifier: Apache-2.0
#pragma once
// Drivetrain plugin: forward kinematics (odometry) and inverse kinematics (setpoints).

#include <span>

#include "swivel/plugin/abi.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/types.hpp"

namespace swivel {

class Drivetrain {
 public:
  virtual ~Drivetrain() = default;

  /// Off the loop. Takes geometry from ctx.robot and limits from ctx.params.
  /// @throws ConfigError naming the key.
  virtual void configure(const PluginContext& ctx) = 0;

  [[nodiscard]] virtual std::uint32_t module_count() const noexcept = 0;

  /// Real-time safe. Odometry between two consecutive readings.
  virtual Status forward(const HardwareState& previous, const HardwareState& current,
                         OdometryIncrement& out) = 0;

  /// Real-time safe. Setpoints for body twist `command` at the current module state,
  /// desaturated to the configured limits; `applied` receives the twist actually commanded.
  virtual Status inverse(const Twist2& command, const HardwareState& current, double dt_s,
                         ActuatorCommand& out, Twist2& applied) = 0;

  /// Real-time safe. Per-module state after the last inverse()/forward() (size module_count()).
  virtual void module_states(std::span<ModuleState> out) const noexcept = 0;

  [[nodiscard]] virtual const char* last_error() const noexcept { return ""; }
};

}  // namespace swivel

// The fingerprint SWIVEL_EXPORT_PLUGIN puts in the descriptor; it needs this interface whole.
#include "swivel/plugin/abi_fingerprint.hpp"  // IWYU pragma: export
