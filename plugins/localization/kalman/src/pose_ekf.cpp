// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/pose_ekf.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <numbers>

namespace swivel::localization {
namespace {

double wrap(double a) noexcept { return std::remainder(a, 2.0 * std::numbers::pi); }

// Smallest variance used where a reading could otherwise be treated as perfect against a
// perfect one (0/0); far below any physical noise.
constexpr double kVarianceFloor = 1e-30;

}  // namespace

bool is_psd(const Eigen::Matrix<double, 4, 4>& m) noexcept {
  if (!m.allFinite()) return false;
  const double scale = m.diagonal().cwiseAbs().maxCoeff();
  if (scale == 0.0) return true;
  const Eigen::LDLT<Eigen::Matrix<double, 4, 4>> ldlt(m);
  if (ldlt.info() != Eigen::Success) return false;
  // Pivoted LDL^T of a PSD matrix has D >= 0; allow rounding relative to the largest entry.
  return ldlt.vectorD().minCoeff() >= -1e-12 * scale;
}

PoseEkf::PoseEkf() noexcept {
  x_.setZero();
  p_.setZero();
}

void PoseEkf::reset(const Pose2& pose, const Matrix3& pose_cov, double bias_radps,
                    double bias_var) noexcept {
  x_ << pose.x_m, pose.y_m, wrap(pose.yaw_rad), bias_radps;
  p_.setZero();
  p_.topLeftCorner<3, 3>() = 0.5 * (pose_cov + pose_cov.transpose());
  p_(3, 3) = bias_var;
}

EkfResult PoseEkf::set_pose(const Pose2& pose, const Matrix3* pose_cov) noexcept {
  if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.yaw_rad)) {
    return EkfResult::kNonFinite;
  }
  if (pose_cov != nullptr) {
    if (!pose_cov->allFinite()) return EkfResult::kNonFinite;
    Matrix4 p = p_;
    p.topLeftCorner<3, 3>() = 0.5 * (*pose_cov + pose_cov->transpose());
    p.topRightCorner<3, 1>().setZero();
    p.bottomLeftCorner<1, 3>().setZero();
    if (!is_psd(p)) return EkfResult::kNotPsd;
    p_ = p;
  }
  x_(0) = pose.x_m;
  x_(1) = pose.y_m;
  x_(2) = wrap(pose.yaw_rad);
  return EkfResult::kOk;
}

EkfResult PoseEkf::step(const Pose2& delta, double dt_s, double gyro_wz_radps,
                        bool gyro_valid) noexcept {
  if (!std::isfinite(delta.x_m) || !std::isfinite(delta.y_m) || !std::isfinite(delta.yaw_rad) ||
      !std::isfinite(dt_s) || !(dt_s > 0.0) || (gyro_valid && !std::isfinite(gyro_wz_radps))) {
    return EkfResult::kNonFinite;
  }
  const double u = delta.yaw_rad;
  const double d = std::hypot(delta.x_m, delta.y_m);
  const EkfNoise& n = noise_;
  const double q_o = n.rotation_rad_per_sqrt_rad * n.rotation_rad_per_sqrt_rad * std::abs(u) +
                     n.yaw_rad_per_sqrt_m * n.yaw_rad_per_sqrt_m * d;

  double rotation = u;
  double drot_dbias = 0.0;
  double q_rot = q_o;
  if (gyro_valid) {
    const double g = gyro_wz_radps * dt_s;
    const double gyro_sd = n.gyro_noise_radps * dt_s;
    const double q_g = gyro_sd * gyro_sd + kVarianceFloor;

    // Gyro update of the bias (H = [0 0 0 1]), Joseph form.
    const double r_var = (q_o + q_g) / (dt_s * dt_s);
    const double s = p_(3, 3) + r_var;
    const Vector4 k = p_.col(3) / s;
    const double innovation = (g - u) / dt_s - x_(3);
    x_ += k * innovation;
    Matrix4 a = Matrix4::Identity();
    a.col(3) -= k;
    p_ = a * p_ * a.transpose() + (k * k.transpose()) * r_var;

    const double w = q_o / (q_o + q_g);
    rotation = u + w * (g - x_(3) * dt_s - u);
    drot_dbias = -w * dt_s;
    q_rot = q_o * q_g / (q_o + q_g);
  }

  // The increment's chord turns by half the difference between the rotation used and the
  // odometry's (see EgOdometry::step).
  const double chord = x_(2) + 0.5 * (rotation - u);
  const double c = std::cos(chord);
  const double sn = std::sin(chord);
  const double jx = -sn * delta.x_m - c * delta.y_m;  // d(world dx)/d(chord)
  const double jy = c * delta.x_m - sn * delta.y_m;   // d(world dy)/d(chord)
  x_(0) += c * delta.x_m - sn * delta.y_m;
  x_(1) += sn * delta.x_m + c * delta.y_m;
  x_(2) = wrap(x_(2) + rotation);

  Matrix4 f = Matrix4::Identity();
  f(0, 2) = jx;
  f(1, 2) = jy;
  f(0, 3) = 0.5 * jx * drot_dbias;
  f(1, 3) = 0.5 * jy * drot_dbias;
  f(2, 3) = drot_dbias;
  const double q_t = n.translation_m_per_sqrt_m * n.translation_m_per_sqrt_m * d;
  const double q_b = n.bias_walk_radps_per_sqrt_s * n.bias_walk_radps_per_sqrt_s * dt_s;
  p_ = f * p_ * f.transpose();
  p_(0, 0) += q_t;
  p_(1, 1) += q_t;
  p_(2, 2) += q_rot;
  p_(3, 3) += q_b;
  return finish_covariance();
}

EkfResult PoseEkf::update_pose_fix(const Pose2& fix) noexcept {
  if (!std::isfinite(fix.x_m) || !std::isfinite(fix.y_m) || !std::isfinite(fix.yaw_rad)) {
    return EkfResult::kNonFinite;
  }
  const double pos_var = noise_.fix_position_noise_m * noise_.fix_position_noise_m;
  const double yaw_var = noise_.fix_yaw_noise_rad * noise_.fix_yaw_noise_rad;
  Matrix3 r = Matrix3::Zero();
  r.diagonal() << pos_var + kVarianceFloor, pos_var + kVarianceFloor, yaw_var + kVarianceFloor;

  const Eigen::Vector3d innovation(fix.x_m - x_(0), fix.y_m - x_(1), wrap(fix.yaw_rad - x_(2)));
  // H = [I3 0]: H P H' is the pose block, P H' its first three columns.
  const Matrix3 s = p_.topLeftCorner<3, 3>() + r;
  const Eigen::Matrix<double, 4, 3> k = p_.leftCols<3>() * s.inverse();
  x_ += k * innovation;
  x_(2) = wrap(x_(2));
  Matrix4 a = Matrix4::Identity();
  a.leftCols<3>() -= k;
  p_ = a * p_ * a.transpose() + k * r * k.transpose();
  return finish_covariance();
}

EkfResult PoseEkf::finish_covariance() noexcept {
  // Through a temporary: assigning p_ + p_.transpose() to p_ directly would alias.
  const Matrix4 symmetric = 0.5 * (p_ + p_.transpose());
  p_ = symmetric;
  return is_psd(p_) ? EkfResult::kOk : EkfResult::kNotPsd;
}

Pose2 PoseEkf::pose() const noexcept { return Pose2{x_(0), x_(1), x_(2)}; }

void PoseEkf::pose_covariance(std::array<double, 9>& out) const noexcept {
  for (Eigen::Index r = 0; r < 3; ++r) {
    for (Eigen::Index c = 0; c < 3; ++c) out[static_cast<std::size_t>(3 * r + c)] = p_(r, c);
  }
}

}  // namespace swivel::localization
