// SPDX-License-Identifier: Apache-2.0
#pragma once
// The `lsm` localization plugin: E/G dead reckoning compensated by LCALSM
// (swivel/localization/lcalsm.hpp).
//
// Covariance: the E/G's, propagated by the E/G noise model (eg_covariance.hpp), plus c c^T
// for the compensation's shift c of the output from the E/G position. The model explains
// the E/G's error; a fit that moves the output away from it (on a straight line, by less
// than the noise it removes; on a curve the fit does not see as a turn, by up to the arc's
// sagitta) is counted in full. In mode heading_aligned, where the shift removes the E/G's
// lateral drift, this is an upper bound.

#include "swivel/localization/eg_covariance.hpp"
#include "swivel/localization/eg_odometry.hpp"
#include "swivel/localization/lcalsm.hpp"
#include "swivel/plugin/localization.hpp"

namespace swivel::plugins {

class LsmLocalization final : public Localization {
 public:
  /// Off the loop. Params (all optional): mode paper|heading_aligned (default paper),
  /// window_points (k, 3..64, default 10), sample_distance_m (default 0.02; 0 when only
  /// sample_period_s is given), sample_period_s (default 0: off),
  /// max_window_heading_change_rad (default 0.1), heading_source gyro|encoders, and the E/G
  /// noise model's keys (localization::read_eg_noise()). @throws ConfigError naming the key.
  void configure(const PluginContext& ctx) override;

  /// Configures from plain values (tests, tools) and resets to the origin, zero covariance.
  void configure(const localization::EgConfig& eg, const localization::LsmConfig& lsm,
                 const localization::EgNoise& noise = {}) noexcept;

  /// Off the loop. Starts at `initial`, with its covariance when it has a valid one.
  void reset(const PoseEstimate& initial) override;

  /// Real-time safe. Restarts the E/G at the handed pose and forgets the stored samples, so
  /// the output equals the handed pose exactly; takes the covariance when `current` has one
  /// (kError, nothing changed, when it is not finite and positive semi-definite), else keeps
  /// the E/G's own.
  Status hand_over(const PoseEstimate& current) noexcept override;

  /// Real-time safe. Ignores cycles whose odometry is not valid.
  Status update(const OdometryIncrement& odometry, const HardwareState& readings) noexcept override;

  /// Real-time safe. Pose with covariance.
  [[nodiscard]] PoseEstimate estimate() const noexcept override;

  /// Real-time safe. Static message for the last kError.
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

  [[nodiscard]] const localization::Lcalsm& lsm() const noexcept { return lsm_; }
  [[nodiscard]] Pose2 raw_eg() const noexcept { return eg_.pose(); }
  [[nodiscard]] const localization::EgCovariance& eg_covariance() const noexcept { return cov_; }

 private:
  localization::EgOdometry eg_;
  localization::EgCovariance cov_;
  localization::Lcalsm lsm_;
  double stamp_s_ = 0.0;
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
