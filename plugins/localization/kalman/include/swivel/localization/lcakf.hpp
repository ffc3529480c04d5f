// SPDX-License-Identifier: Apache-2.0
#pragma once
// LCAKF of docs/methods.md §2: a linear Kalman filter on the position coordinates, fed with the
// E/G positions as measurements. The paper gives no model; this one is a constant-velocity
// model per axis (state x, vx, y, vy; x and y independent), white acceleration process
// noise, and the E/G position as a direct measurement with white noise. The heading is the
// E/G heading, passed through. Plain maths, fixed-size; every method is real-time safe.

#include <Eigen/Core>

#include "swivel/types.hpp"

namespace swivel::localization {

struct LcakfNoise {
  double accel_mps2 = 0.5;   ///< std of the white acceleration driving each axis
  double position_m = 0.01;  ///< std of an E/G position measurement
};

class Lcakf {
 public:
  using Vector2 = Eigen::Matrix<double, 2, 1>;
  using Matrix2 = Eigen::Matrix<double, 2, 2>;

  Lcakf() noexcept;

  void set_noise(const LcakfNoise& noise) noexcept { noise_ = noise; }
  [[nodiscard]] const LcakfNoise& noise() const noexcept { return noise_; }

  /// Starts at (x, y) at rest with position variance `position_var` on each axis.
  void reset(double x_m, double y_m, double position_var) noexcept;
  /// Overwrites the positions (velocities kept); and their variances when given (>= 0).
  void set_position(double x_m, double y_m, double x_var, double y_var) noexcept;

  /// Constant-velocity prediction over dt_s, then the update with measurement (x, y).
  /// Returns false (state unchanged) on non-finite input or dt_s <= 0, or when the
  /// covariance is not positive semi-definite afterwards.
  bool step(double dt_s, double measured_x_m, double measured_y_m) noexcept;

  [[nodiscard]] double x_m() const noexcept { return x_(0); }
  [[nodiscard]] double y_m() const noexcept { return y_(0); }
  [[nodiscard]] double vx_mps() const noexcept { return x_(1); }
  [[nodiscard]] double vy_mps() const noexcept { return y_(1); }
  [[nodiscard]] const Matrix2& covariance_x() const noexcept { return px_; }
  [[nodiscard]] const Matrix2& covariance_y() const noexcept { return py_; }

 private:
  LcakfNoise noise_{};
  Vector2 x_;  // (x, vx)
  Vector2 y_;  // (y, vy)
  Matrix2 px_;
  Matrix2 py_;
};

}  // namespace swivel::localization
