// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/eg_covariance.hpp"

#include <Eigen/Cholesky>
#include <cmath>

namespace swivel::localization {

bool is_covariance(const Eigen::Matrix3d& m) noexcept {
  if (!m.allFinite()) return false;
  const double scale = m.diagonal().cwiseAbs().maxCoeff();
  if (scale == 0.0) return m.isZero(0.0);
  if (!m.isApprox(m.transpose(), 1e-9)) return false;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(m);
  if (ldlt.info() != Eigen::Success) return false;
  // Pivoted LDL^T of a PSD matrix has D >= 0; allow rounding relative to the largest entry.
  return ldlt.vectorD().minCoeff() >= -1e-12 * scale;
}

EgCovariance::EgCovariance() noexcept { p_.setZero(); }

void EgCovariance::reset(const Matrix3& pose_cov) noexcept {
  p_.setZero();
  p_.topLeftCorner<3, 3>() = 0.5 * (pose_cov + pose_cov.transpose());
  p_(3, 3) = noise_.gyro_bias_sigma_radps * noise_.gyro_bias_sigma_radps;
}

bool EgCovariance::set_pose_covariance(const Matrix3& pose_cov) noexcept {
  if (!is_covariance(pose_cov)) return false;
  p_.topLeftCorner<3, 3>() = 0.5 * (pose_cov + pose_cov.transpose());
  p_.topRightCorner<3, 1>().setZero();
  p_.bottomLeftCorner<1, 3>().setZero();
  return true;
}

void EgCovariance::step(const Pose2& delta, double dt_s, double chord_yaw_rad,
                        bool used_gyro) noexcept {
  const EgNoise& n = noise_;
  const double d = std::hypot(delta.x_m, delta.y_m);
  double q_yaw = 0.0;
  double dchord_dbias = 0.0;
  Matrix4 f = Matrix4::Identity();
  if (used_gyro) {
    const double sd = n.gyro_noise_radps * dt_s;
    q_yaw = sd * sd;
    f(2, 3) = dt_s;
    dchord_dbias = 0.5 * dt_s;
  } else {
    q_yaw = n.rotation_rad_per_sqrt_rad * n.rotation_rad_per_sqrt_rad * std::abs(delta.yaw_rad) +
            n.yaw_rad_per_sqrt_m * n.yaw_rad_per_sqrt_m * d;
  }
  const double c = std::cos(chord_yaw_rad);
  const double s = std::sin(chord_yaw_rad);
  const double jx = -s * delta.x_m - c * delta.y_m;  // d(world dx)/d(chord)
  const double jy = c * delta.x_m - s * delta.y_m;   // d(world dy)/d(chord)
  f(0, 2) = jx;
  f(1, 2) = jy;
  f(0, 3) = jx * dchord_dbias;
  f(1, 3) = jy * dchord_dbias;
  const Matrix4 propagated = f * p_ * f.transpose();
  p_ = propagated;

  if (d > 0.0) {
    // Along and across the step's direction in the world: (dx, dy) / d turned by the chord.
    const Eigen::Vector2d along((c * delta.x_m - s * delta.y_m) / d,
                                (s * delta.x_m + c * delta.y_m) / d);
    const Eigen::Vector2d across(-along.y(), along.x());
    p_.topLeftCorner<2, 2>() +=
        (n.along_track_m_per_sqrt_m * n.along_track_m_per_sqrt_m * d) * along * along.transpose() +
        (n.cross_track_m_per_sqrt_m * n.cross_track_m_per_sqrt_m * d) * across * across.transpose();
  }
  p_(2, 2) += q_yaw;
  p_(3, 3) += n.bias_walk_radps_per_sqrt_s * n.bias_walk_radps_per_sqrt_s * dt_s;
  const Matrix4 symmetric = 0.5 * (p_ + p_.transpose());
  p_ = symmetric;
}

void EgCovariance::pose_covariance(std::array<double, 9>& out) const noexcept {
  // The pose block (x, y, yaw), row by row.
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(out.data()) = p_.topLeftCorner<3, 3>();
}

}  // namespace swivel::localization
