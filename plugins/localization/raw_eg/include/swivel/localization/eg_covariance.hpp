// SPDX-License-Identifier: Apache-2.0
#pragma once
// The uncertainty of E/G dead reckoning (eg_odometry.hpp): a first-order propagation of the
// error in (x, y, yaw, b), b the gyro bias left after the nominal correction (rad/s of true
// rate), through the same steps EgOdometry takes. Plain maths, fixed-size: nothing
// allocates and every method is real-time safe.
//
// Noise model, per step with translation (dx, dy) in the robot frame, length d, odometry
// heading change u and duration dt:
// - translation: white, variance along_track^2 d along the step's direction and
//   cross_track^2 d across it (per-metre growth: the position std after a straight run of
//   L metres is along_track * sqrt(L) along it);
// - heading from the gyro: (gyro_noise dt)^2 (gyro_noise the per-sample standard deviation
//   of the corrected rate), and the residual bias b turns the heading by b dt and the step's
//   chord by b dt / 2;
// - heading from the encoders: rotation^2 |u| + yaw_per_m^2 d (per-radian and per-metre
//   growth), independent of b;
// - b: starts with variance gyro_bias_sigma^2 and walks with bias_walk^2 dt per step.
// The heading error turns the step's translation: the position picks up the Jacobian of the
// chord rotation, which is what correlates position and heading.

#include <Eigen/Core>
#include <array>

#include "swivel/types.hpp"

namespace swivel::localization {

struct EgNoise {
  double along_track_m_per_sqrt_m = 0.01;   ///< position std along the motion per sqrt(m)
  double cross_track_m_per_sqrt_m = 0.01;   ///< position std across the motion per sqrt(m)
  double rotation_rad_per_sqrt_rad = 0.05;  ///< encoder heading std per sqrt(rad turned)
  double yaw_rad_per_sqrt_m = 0.01;         ///< encoder heading std per sqrt(m travelled)
  double gyro_noise_radps = 0.0;            ///< per-sample std of the corrected gyro rate
  double gyro_bias_sigma_radps = 0.0;       ///< residual bias std after the nominal correction
  double bias_walk_radps_per_sqrt_s = 0.0;  ///< residual bias random walk
};

/// True when `m` is finite and symmetric positive semi-definite to rounding.
bool is_covariance(const Eigen::Matrix3d& m) noexcept;

class EgCovariance {
 public:
  using Matrix3 = Eigen::Matrix3d;
  using Matrix4 = Eigen::Matrix4d;

  EgCovariance() noexcept;

  void set_noise(const EgNoise& noise) noexcept { noise_ = noise; }
  [[nodiscard]] const EgNoise& noise() const noexcept { return noise_; }

  /// Pose covariance `pose_cov` (x, y, yaw), bias variance gyro_bias_sigma^2, uncorrelated.
  void reset(const Matrix3& pose_cov) noexcept;

  /// Overwrites the pose block (its correlation with the bias dropped; the bias variance
  /// kept). False, nothing changed, unless `pose_cov` is a covariance (is_covariance()).
  bool set_pose_covariance(const Matrix3& pose_cov) noexcept;

  /// One EgOdometry::step: the robot-frame `delta` it integrated, the step's duration, the
  /// chord heading it turned the translation by (EgOdometry::last_chord_yaw_rad()) and
  /// whether its heading came from the gyro.
  void step(const Pose2& delta, double dt_s, double chord_yaw_rad, bool used_gyro) noexcept;

  /// Row-major over (x, y, yaw), as PoseEstimate::covariance.
  void pose_covariance(std::array<double, 9>& out) const noexcept;
  [[nodiscard]] const Matrix4& covariance() const noexcept { return p_; }

 private:
  EgNoise noise_{};
  Matrix4 p_;
};

}  // namespace swivel::localization
