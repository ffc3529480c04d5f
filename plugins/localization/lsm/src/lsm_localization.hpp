#pragma once
// The `lsm` localization plugin: E/G dead reckoning compensated by LCALSM
// (swivel/localization/lcalsm.hpp). No covariance.

#include "swivel/localization/eg_odometry.hpp"
#include "swivel/localization/lcalsm.hpp"
#include "swivel/plugin/localization.hpp"

namespace swivel::plugins {

class LsmLocalization final : public Localization {
 public:
  /// Off the loop. Params (all optional): mode paper|heading_aligned (default paper),
  /// window_points (k, 3..64, default 10), sample_distance_m (default 0.02; 0 when only
  /// sample_period_s is given), sample_period_s (default 0: off),
  /// max_window_heading_change_rad (default 0.1), heading_source gyro|encoders.
  /// @throws ConfigError naming the key.
  void configure(const PluginContext& ctx) override;

  /// Configures from plain values (tests, tools) and resets to the origin.
  void configure(const localization::EgConfig& eg, const localization::LsmConfig& lsm) noexcept;

  /// Off the loop.
  void reset(const PoseEstimate& initial) override;

  /// Real-time safe. Restarts the E/G at the handed pose and forgets the stored samples, so
  /// the output equals the handed pose exactly.
  Status hand_over(const PoseEstimate& current) noexcept override;

  /// Real-time safe. Ignores cycles whose odometry is not valid.
  Status update(const OdometryIncrement& odometry, const HardwareState& readings) noexcept override;

  /// Real-time safe.
  [[nodiscard]] PoseEstimate estimate() const noexcept override;

  /// Real-time safe. Static message for the last kError.
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

  [[nodiscard]] const localization::Lcalsm& lsm() const noexcept { return lsm_; }
  [[nodiscard]] Pose2 raw_eg() const noexcept { return eg_.pose(); }

 private:
  localization::EgOdometry eg_;
  localization::Lcalsm lsm_;
  double stamp_s_ = 0.0;
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
