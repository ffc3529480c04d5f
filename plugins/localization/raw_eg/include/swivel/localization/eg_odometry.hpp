// SPDX-License-Identifier: Apache-2.0
#pragma once
// E/G (encoder/gyro) dead reckoning of docs/methods.md §2 eq. (1)-(6), driven by a drivetrain's
// odometry increment so that it serves the differential robot and the holonomic SWPC
// robot alike. Plain maths: no threads, no YAML. Every method is real-time safe.

#include "swivel/types.hpp"

namespace swivel::localization {

enum class HeadingSource : unsigned char {
  kGyro = 0,      ///< eq. (4): integrated gyro rate (odometry when the gyro is invalid)
  kEncoders = 1,  ///< eq. (4) alternative: the drivetrain's heading increment
};

struct EgConfig {
  HeadingSource heading_source = HeadingSource::kGyro;
  /// Gyro model of eq. (7), w_measured = scale * w_true + bias: the reading is corrected to
  /// (w_measured - bias) / scale before it is integrated.
  double gyro_scale = 1.0;
  double gyro_bias_radps = 0.0;
};

/// Wraps an angle to [-pi, pi].
double wrap_angle(double angle_rad) noexcept;

class EgOdometry {
 public:
  EgOdometry() noexcept = default;
  explicit EgOdometry(const EgConfig& config) noexcept : config_(config) {}

  void set_config(const EgConfig& config) noexcept { config_ = config; }
  [[nodiscard]] const EgConfig& config() const noexcept { return config_; }

  /// Starts from `pose` (its yaw is kept unwrapped internally).
  void reset(const Pose2& pose) noexcept;

  /// One step. `delta` is the drivetrain's motion in the robot frame at the start of the
  /// step (x and y both used, so holonomic motion is integrated too). The heading change is
  /// the gyro's (corrected rate times dt_s) or the odometry's, per the configuration. The
  /// translation is turned into the world frame at the start heading plus half the
  /// difference between the heading change used and the odometry's: the chord of an arc
  /// points half-way through the turn, so this is eq. (5)-(6) at the mid-step heading and
  /// exact on circular arcs. Returns false (state unchanged) on non-finite input.
  bool step(const Pose2& delta, double dt_s, double gyro_wz_radps, bool gyro_valid) noexcept;

  /// Pose with the yaw wrapped to [-pi, pi].
  [[nodiscard]] Pose2 pose() const noexcept;
  /// Yaw without wrapping: continuous across turns.
  [[nodiscard]] double unwrapped_yaw_rad() const noexcept { return yaw_rad_; }
  /// Path length travelled since reset (sum of |translation| per step).
  [[nodiscard]] double distance_m() const noexcept { return distance_m_; }
  /// True when the last step took its heading from the gyro.
  [[nodiscard]] bool last_step_used_gyro() const noexcept { return last_used_gyro_; }
  /// The heading the last step turned its translation into the world frame by (unwrapped).
  [[nodiscard]] double last_chord_yaw_rad() const noexcept { return last_chord_yaw_rad_; }

 private:
  EgConfig config_{};
  double x_m_ = 0.0;
  double y_m_ = 0.0;
  double yaw_rad_ = 0.0;
  double distance_m_ = 0.0;
  bool last_used_gyro_ = false;
  double last_chord_yaw_rad_ = 0.0;
};

}  // namespace swivel::localization
