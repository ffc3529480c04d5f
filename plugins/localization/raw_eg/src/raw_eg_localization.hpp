// SPDX-License-Identifier: Apache-2.0
#pragma once
// The `raw_eg` localization plugin: E/G dead reckoning (swivel/localization/eg_odometry.hpp)
// behind the Localization interface, with its covariance propagated by the E/G noise model
// (swivel/localization/eg_covariance.hpp).

#include "swivel/localization/eg_covariance.hpp"
#include "swivel/localization/eg_odometry.hpp"
#include "swivel/plugin/localization.hpp"

namespace swivel::plugins {

class RawEgLocalization final : public Localization {
 public:
  /// Off the loop. Params: heading_source gyro (default) | encoders, and the noise model's
  /// keys (localization::read_eg_noise()). The gyro reading is corrected with the nominal
  /// robot model's sensors.gyro scale and bias. @throws ConfigError naming the key.
  void configure(const PluginContext& ctx) override;

  /// Configures from plain values (tests, tools) and resets to the origin with zero
  /// covariance.
  void configure(const localization::EgConfig& config,
                 const localization::EgNoise& noise = {}) noexcept;

  /// Off the loop. Starts at `initial`, with its covariance when it has a valid one (else
  /// zero: the start pose is the origin of the odometry).
  void reset(const PoseEstimate& initial) override;

  /// Real-time safe. Takes the pose, and the covariance when `current` has one (kError,
  /// nothing changed, when it is not finite or not positive semi-definite); without one,
  /// keeps its own.
  Status hand_over(const PoseEstimate& current) noexcept override;

  /// Real-time safe. Ignores cycles whose odometry is not valid.
  Status update(const OdometryIncrement& odometry, const HardwareState& readings) noexcept override;

  /// Real-time safe. Pose with covariance.
  [[nodiscard]] PoseEstimate estimate() const noexcept override;

  /// Real-time safe. Static message for the last kError.
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

  [[nodiscard]] const localization::EgCovariance& covariance() const noexcept { return cov_; }

 private:
  localization::EgOdometry eg_;
  localization::EgCovariance cov_;
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
