// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/lcakf.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace swivel::localization {
namespace {

using Vector2 = Lcakf::Vector2;
using Matrix2 = Lcakf::Matrix2;

// One axis: predict with F = [1 dt; 0 1], Q = discrete white acceleration, then update
// with H = [1 0] in Joseph form. Works on copies so that a failure changes nothing.
bool axis_step(Vector2& s, Matrix2& p, double dt_s, double z, double accel_var,
               double meas_var) noexcept {
  Matrix2 f;
  f << 1.0, dt_s, 0.0, 1.0;
  const double dt2 = dt_s * dt_s;
  Matrix2 q;
  q << 0.25 * dt2 * dt2, 0.5 * dt2 * dt_s, 0.5 * dt2 * dt_s, dt2;
  Vector2 s_new = f * s;
  Matrix2 p_new = f * p * f.transpose() + q * accel_var;

  const double innovation_var = p_new(0, 0) + meas_var;
  if (!(innovation_var > 0.0)) return false;
  const Vector2 k = p_new.col(0) / innovation_var;
  s_new += k * (z - s_new(0));
  Matrix2 a = Matrix2::Identity();
  a.col(0) -= k;
  p_new = a * p_new * a.transpose() + (k * k.transpose()) * meas_var;
  const Matrix2 symmetric = 0.5 * (p_new + p_new.transpose());  // a temporary: no aliasing
  p_new = symmetric;
  // 2x2 symmetric PSD: both diagonal entries and the determinant non-negative.
  const double tol = 1e-12 * std::max(p_new(0, 0), p_new(1, 1));
  if (!p_new.allFinite() || p_new(0, 0) < -tol || p_new(1, 1) < -tol ||
      p_new.determinant() < -tol * tol) {
    return false;
  }
  s = s_new;
  p = p_new;
  return true;
}

}  // namespace

Lcakf::Lcakf() noexcept { reset(0.0, 0.0, 0.0); }

void Lcakf::reset(double x_m, double y_m, double position_var) noexcept {
  x_ << x_m, 0.0;
  y_ << y_m, 0.0;
  // Velocity unknown at start: a prior wide enough for any docent speed (1 m/s std).
  px_ << position_var, 0.0, 0.0, 1.0;
  py_ = px_;
}

void Lcakf::set_position(double x_m, double y_m, double x_var, double y_var) noexcept {
  x_(0) = x_m;
  y_(0) = y_m;
  if (x_var >= 0.0) {
    px_(0, 0) = x_var;
    px_(0, 1) = px_(1, 0) = 0.0;
  }
  if (y_var >= 0.0) {
    py_(0, 0) = y_var;
    py_(0, 1) = py_(1, 0) = 0.0;
  }
}

bool Lcakf::step(double dt_s, double measured_x_m, double measured_y_m) noexcept {
  if (!std::isfinite(dt_s) || !(dt_s > 0.0) || !std::isfinite(measured_x_m) ||
      !std::isfinite(measured_y_m)) {
    return false;
  }
  const double accel_var = noise_.accel_mps2 * noise_.accel_mps2;
  const double meas_var = noise_.position_m * noise_.position_m;
  Vector2 x = x_;
  Vector2 y = y_;
  Matrix2 px = px_;
  Matrix2 py = py_;
  if (!axis_step(x, px, dt_s, measured_x_m, accel_var, meas_var)) return false;
  if (!axis_step(y, py, dt_s, measured_y_m, accel_var, meas_var)) return false;
  x_ = x;
  y_ = y;
  px_ = px;
  py_ = py;
  return true;
}

}  // namespace swivel::localization
