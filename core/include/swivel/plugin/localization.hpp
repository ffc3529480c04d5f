// SPDX-License-Identifier: Apache-2.0
#pragma once
// Localization plugin: pose (and covariance) from odometry increments, gyro and, where a
// source provides them, absolute pose fixes (HardwareState::motion_capture).

#include "swivel/plugin/abi.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/types.hpp"

namespace swivel {

class Localization {
 public:
  virtual ~Localization() = default;

  /// Off the loop. @throws ConfigError naming the key.
  virtual void configure(const PluginContext& ctx) = 0;

  /// Off the loop. Starts from `initial` (hand-over on a hot swap: the outgoing
  /// instance's estimate). Ignores the covariance when it has none.
  virtual void reset(const PoseEstimate& initial) = 0;

  /// Real-time safe. Called by the loop at the cycle it takes this instance in a hot swap,
  /// with the outgoing instance's estimate at that cycle, so that the pose is continuous.
  /// Overwrites pose (and covariance when `current` has one) without allocating.
  virtual Status hand_over(const PoseEstimate& current) = 0;

  /// Real-time safe. One cycle: the drivetrain's odometry and this cycle's readings.
  virtual Status update(const OdometryIncrement& odometry, const HardwareState& readings) = 0;

  /// Real-time safe. The current output.
  [[nodiscard]] virtual PoseEstimate estimate() const noexcept = 0;

  [[nodiscard]] virtual const char* last_error() const noexcept { return ""; }
};

}  // namespace swivel

// The fingerprint SWIVEL_EXPORT_PLUGIN puts in the descriptor; it needs this interface whole.
#include "swivel/plugin/abi_fingerprint.hpp"  // IWYU pragma: export
