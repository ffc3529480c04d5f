// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/eg_odometry.hpp"

#include <cmath>
#include <numbers>

namespace swivel::localization {

double wrap_angle(double angle_rad) noexcept {
  return std::remainder(angle_rad, 2.0 * std::numbers::pi);
}

void EgOdometry::reset(const Pose2& pose) noexcept {
  x_m_ = pose.x_m;
  y_m_ = pose.y_m;
  yaw_rad_ = pose.yaw_rad;
  distance_m_ = 0.0;
  last_used_gyro_ = false;
  last_chord_yaw_rad_ = pose.yaw_rad;
}

bool EgOdometry::step(const Pose2& delta, double dt_s, double gyro_wz_radps,
                      bool gyro_valid) noexcept {
  if (!std::isfinite(delta.x_m) || !std::isfinite(delta.y_m) || !std::isfinite(delta.yaw_rad) ||
      !std::isfinite(dt_s)) {
    return false;
  }
  const bool use_gyro = config_.heading_source == HeadingSource::kGyro && gyro_valid;
  double dyaw_rad = delta.yaw_rad;
  if (use_gyro) {
    if (!std::isfinite(gyro_wz_radps)) return false;
    dyaw_rad = (gyro_wz_radps - config_.gyro_bias_radps) / config_.gyro_scale * dt_s;
  }
  const double chord_yaw_rad = yaw_rad_ + 0.5 * (dyaw_rad - delta.yaw_rad);
  const double c = std::cos(chord_yaw_rad);
  const double s = std::sin(chord_yaw_rad);
  x_m_ += c * delta.x_m - s * delta.y_m;  // eq. (5)
  y_m_ += s * delta.x_m + c * delta.y_m;  // eq. (6)
  yaw_rad_ += dyaw_rad;
  distance_m_ += std::hypot(delta.x_m, delta.y_m);
  last_used_gyro_ = use_gyro;
  last_chord_yaw_rad_ = chord_yaw_rad;
  return true;
}

Pose2 EgOdometry::pose() const noexcept { return Pose2{x_m_, y_m_, wrap_angle(yaw_rad_)}; }

}  // namespace swivel::localization
