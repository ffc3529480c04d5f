// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/reading_gap.hpp"

#include <algorithm>
#include <cmath>

#include "swivel/pose_math.hpp"

namespace swivel::rt {
namespace {

double sigma_of(const std::array<double, 9>& covariance, std::size_t axis) noexcept {
  return std::sqrt(std::max(covariance[axis * 4], 0.0));
}

}  // namespace

void ReadingGap::begin(const PoseEstimate& estimate, const Twist2& twist,
                       const std::array<double, 9>* twist_covariance, double since_s) noexcept {
  active_ = true;
  has_twist_ = true;
  start_ = estimate;
  estimate_ = estimate;
  measured_ = twist;
  has_twist_covariance_ = twist_covariance != nullptr;
  measured_sigma_ = {};
  if (twist_covariance != nullptr) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      measured_sigma_[axis] = sigma_of(*twist_covariance, axis);
    }
  }
  last_s_ = since_s;
  position_sigma_m_ = 0.0;
  heading_sigma_rad_ = 0.0;
  advance(twist, since_s);
}

void ReadingGap::advance(const Twist2& model, double now_s) noexcept {
  integrate(now_s);
  twist_ = model;
  // Between braking as modelled and still moving as last measured.
  twist_covariance_ = {};
  const std::array<double, 3> apart{std::abs(model.vx_mps - measured_.vx_mps),
                                    std::abs(model.vy_mps - measured_.vy_mps),
                                    std::abs(model.wz_radps - measured_.wz_radps)};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const double sigma = measured_sigma_[axis] + apart[axis];
    twist_covariance_[axis * 4] = sigma * sigma;
  }
}

void ReadingGap::integrate(double now_s) noexcept {
  const double dt_s = std::max(now_s - last_s_, 0.0);
  last_s_ = now_s;
  if (dt_s == 0.0) return;
  Pose2& p = estimate_.pose;
  const double yaw_mid = p.yaw_rad + 0.5 * twist_.wz_radps * dt_s;
  const double c = std::cos(yaw_mid);
  const double s = std::sin(yaw_mid);
  p.x_m += (c * twist_.vx_mps - s * twist_.vy_mps) * dt_s;
  p.y_m += (s * twist_.vx_mps + c * twist_.vy_mps) * dt_s;
  p.yaw_rad += twist_.wz_radps * dt_s;
  position_sigma_m_ +=
      std::hypot(sigma_of(twist_covariance_, 0), sigma_of(twist_covariance_, 1)) * dt_s;
  heading_sigma_rad_ += sigma_of(twist_covariance_, 2) * dt_s;
  if (estimate_.has_covariance) {
    estimate_.covariance = start_.covariance;
    estimate_.covariance[0] += position_sigma_m_ * position_sigma_m_;
    estimate_.covariance[4] += position_sigma_m_ * position_sigma_m_;
    estimate_.covariance[8] += heading_sigma_rad_ * heading_sigma_rad_;
  }
}

PoseEstimate ReadingGap::resume(const OdometryIncrement& measured, double now_s) noexcept {
  integrate(now_s);
  active_ = false;
  PoseEstimate handed = estimate_;
  if (!measured.valid) return handed;
  const Pose2 reckoned = between(start_.pose, estimate_.pose);
  position_error_m_ =
      std::hypot(measured.delta.x_m - reckoned.x_m, measured.delta.y_m - reckoned.y_m);
  heading_error_rad_ = std::abs(measured.delta.yaw_rad - reckoned.yaw_rad);
  if (handed.has_covariance) {
    handed.covariance[0] += position_error_m_ * position_error_m_;
    handed.covariance[4] += position_error_m_ * position_error_m_;
    handed.covariance[8] += heading_error_rad_ * heading_error_rad_;
  }
  return handed;
}

}  // namespace swivel::rt
