// SPDX-License-Identifier: Apache-2.0
#pragma once
// Extended Kalman filter over (x, y, yaw, gyro_bias) driven by a drivetrain's odometry
// increment, with the gyro and optional absolute pose fixes as measurements.
// Plain maths: no threads, no YAML. Fixed-size matrices: nothing allocates after
// construction, and every method is real-time safe.
//
// Model, per step of duration dt:
// - Two readings of the same rotation r: the odometry's u = r + n_o, var q_o =
//   rotation^2 |u| + yaw_per_m^2 |d| (d: distance travelled), and the gyro's
//   g = w_g dt = r + b dt + n_g, var q_g = (gyro_noise dt)^2 (gyro_noise is the
//   per-sample standard deviation).
// - Gyro update: the measurement w_g = w_true + b, with w_true from the odometry
//   (w_true = u / dt), i.e. z = (g - u)/dt, h(state) = b, R = (q_o + q_g)/dt^2. It observes
//   the bias whenever the robot is still (q_o = 0: exact) and, more weakly, while it moves.
// - Prediction: the rotation used is the variance-weighted mean of both readings,
//   r = u + q_o/(q_o + q_g) (g - b dt - u), var q_o q_g/(q_o + q_g). Given b, this mean and
//   the difference used by the gyro update are uncorrelated, so the two steps use each
//   reading once. dr/db enters the Jacobian, which is what correlates yaw and bias.
//   Translation: the increment turned into the world at the chord heading (as in E/G),
//   isotropic variance translation^2 |d|; bias random walk var bias_walk^2 dt.
// - Without a valid gyro the rotation is the odometry's alone and the bias is not updated.
// - Pose fix: z = (x, y, yaw), yaw innovation wrapped to [-pi, pi].
// Every covariance update uses the Joseph form, then the covariance is symmetrised and
// checked positive semi-definite.

#include <Eigen/Core>
#include <array>

#include "swivel/types.hpp"

namespace swivel::localization {

struct EkfNoise {
  double translation_m_per_sqrt_m = 0.01;    ///< position std grows as this * sqrt(distance)
  double rotation_rad_per_sqrt_rad = 0.05;   ///< odometry yaw std per sqrt(rad turned)
  double yaw_rad_per_sqrt_m = 0.01;          ///< odometry yaw std per sqrt(m travelled)
  double bias_walk_radps_per_sqrt_s = 1e-5;  ///< gyro bias random walk
  double gyro_noise_radps = 0.002;           ///< per-sample gyro standard deviation
  double fix_position_noise_m = 0.0003;      ///< pose fix position std
  double fix_yaw_noise_rad = 0.001;          ///< pose fix yaw std
};

enum class EkfResult : unsigned char {
  kOk = 0,
  kNonFinite = 1,  ///< an input was not finite; state unchanged
  kNotPsd = 2,     ///< the covariance lost positive semi-definiteness
};

class PoseEkf {
 public:
  using Vector4 = Eigen::Matrix<double, 4, 1>;
  using Matrix4 = Eigen::Matrix<double, 4, 4>;
  using Matrix3 = Eigen::Matrix<double, 3, 3>;

  PoseEkf() noexcept;

  void set_noise(const EkfNoise& noise) noexcept { noise_ = noise; }
  [[nodiscard]] const EkfNoise& noise() const noexcept { return noise_; }

  /// Starts at `pose` with pose covariance `pose_cov` (x, y, yaw), bias `bias_radps` with
  /// variance `bias_var`; no pose-bias correlation.
  void reset(const Pose2& pose, const Matrix3& pose_cov, double bias_radps,
             double bias_var) noexcept;

  /// Overwrites the pose; the pose block of the covariance too when `pose_cov` is given
  /// (its correlation with the bias is then dropped). Bias and its variance are kept.
  EkfResult set_pose(const Pose2& pose, const Matrix3* pose_cov) noexcept;

  /// One step: gyro update (when `gyro_valid`) then prediction with the increment.
  /// `gyro_wz_radps` is the reading already corrected for the nominal scale and bias.
  EkfResult step(const Pose2& delta, double dt_s, double gyro_wz_radps, bool gyro_valid) noexcept;

  /// Absolute pose measurement (e.g. motion capture).
  EkfResult update_pose_fix(const Pose2& fix) noexcept;

  [[nodiscard]] Pose2 pose() const noexcept;
  [[nodiscard]] double bias_radps() const noexcept { return x_(3); }
  [[nodiscard]] const Vector4& state() const noexcept { return x_; }
  [[nodiscard]] const Matrix4& covariance() const noexcept { return p_; }
  /// Pose covariance, row-major over (x, y, yaw), as in PoseEstimate.
  void pose_covariance(std::array<double, 9>& out) const noexcept;

 private:
  EkfResult finish_covariance() noexcept;

  EkfNoise noise_{};
  Vector4 x_;
  Matrix4 p_;
};

/// True when `m` (assumed symmetric) is positive semi-definite to rounding. Real-time safe.
bool is_psd(const Eigen::Matrix<double, 4, 4>& m) noexcept;

}  // namespace swivel::localization
