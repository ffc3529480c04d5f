// SPDX-License-Identifier: Apache-2.0
#pragma once
// The `kalman` localization plugin. mode: ekf (default) runs PoseEkf (pose + gyro bias,
// gyro and motion-capture updates); mode: lcakf runs the paper's LCAKF on E/G positions.

#include "swivel/localization/eg_odometry.hpp"
#include "swivel/localization/lcakf.hpp"
#include "swivel/localization/pose_ekf.hpp"
#include "swivel/plugin/localization.hpp"

namespace swivel::plugins {

enum class KalmanMode : unsigned char { kEkf = 0, kLcakf = 1 };

/// Plain-value configuration (what configure(ctx) reads from params).
struct KalmanConfig {
  KalmanMode mode = KalmanMode::kEkf;
  localization::EkfNoise ekf;
  localization::LcakfNoise lcakf;
  localization::EgConfig eg;  ///< gyro correction (both modes), heading (lcakf)
  double initial_position_sigma_m = 0.0;
  double initial_yaw_sigma_rad = 0.0;
  double initial_bias_sigma_radps = 0.02;
  /// Uncertainty taken on at a hand-over from a plugin that has no covariance (raw_eg,
  /// lsm): a pose from unbounded dead reckoning is not exact, and a filter that starts with
  /// zero covariance would ignore every motion-capture fix for a long time.
  double handover_position_sigma_m = 0.1;
  double handover_yaw_sigma_rad = 0.05;
  bool use_pose_fixes = true;  ///< ekf: update from valid motion-capture samples
};

class KalmanLocalization final : public Localization {
 public:
  /// Off the loop. Params (all optional): mode ekf|lcakf; heading_source gyro|encoders
  /// (lcakf's E/G); translation_noise_m_per_sqrt_m, rotation_noise_rad_per_sqrt_rad,
  /// yaw_noise_rad_per_sqrt_m, bias_random_walk_radps_per_sqrt_s, gyro_noise_radps
  /// (default: robot sensors.gyro.noise_rad_s), fix_position_noise_m, fix_yaw_noise_rad
  /// (default: robot sensors.motion_capture), use_pose_fixes, initial_position_sigma_m,
  /// initial_yaw_sigma_rad, initial_bias_sigma_radps, handover_position_sigma_m (0.1),
  /// handover_yaw_sigma_rad (0.05), lcakf_accel_noise_mps2,
  /// lcakf_position_noise_m. @throws ConfigError naming the key.
  void configure(const PluginContext& ctx) override;

  /// Configures from plain values (tests, tools) and resets to the origin.
  void configure(const KalmanConfig& config) noexcept;

  /// Off the loop. Uses `initial`'s covariance when it has one, else the configured sigmas.
  void reset(const PoseEstimate& initial) override;

  /// Real-time safe. Keeps this filter's bias estimate.
  Status hand_over(const PoseEstimate& current) noexcept override;

  /// Real-time safe. Ignores cycles whose odometry is not valid.
  Status update(const OdometryIncrement& odometry, const HardwareState& readings) noexcept override;

  /// Real-time safe. Pose with covariance (lcakf: yaw variance is the E/G heading's
  /// accumulated odometry/gyro noise, uncorrelated with the positions).
  [[nodiscard]] PoseEstimate estimate() const noexcept override;

  /// Real-time safe. Static message for the last kError.
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

  [[nodiscard]] const KalmanConfig& config() const noexcept { return config_; }
  [[nodiscard]] const localization::PoseEkf& ekf() const noexcept { return ekf_; }
  [[nodiscard]] const localization::Lcakf& lcakf() const noexcept { return lcakf_; }

 private:
  Status fail(const char* message) noexcept {
    last_error_ = message;
    return Status::kError;
  }

  KalmanConfig config_{};
  localization::PoseEkf ekf_;
  localization::Lcakf lcakf_;
  localization::EgOdometry eg_;  // lcakf's measurement source
  double lcakf_yaw_var_ = 0.0;
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
