// SPDX-License-Identifier: Apache-2.0
#include "swivel/swpc/swpc_kinematics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>

namespace swivel::swpc {
namespace {

// Fixed capacity keeps every matrix on the stack: no heap on the real-time loop.
using SystemMatrix = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::ColMajor, 2 * kMaxModules, 3>;
using SystemVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 2 * kMaxModules, 1>;

bool finite_twist(const Twist2& t) noexcept {
  return std::isfinite(t.vx_mps) && std::isfinite(t.vy_mps) && std::isfinite(t.wz_radps);
}

}  // namespace

void steering_axis_velocity(const SwpcModuleParams& m, const Twist2& t, double& vx,
                            double& vy) noexcept {
  vx = t.vx_mps - t.wz_radps * m.y_m;
  vy = t.vy_mps + t.wz_radps * m.x_m;
}

ModuleRates inverse_module(const SwpcModuleParams& m, double phi_rad, const Twist2& t) noexcept {
  double vsx = 0.0;
  double vsy = 0.0;
  steering_axis_velocity(m, t, vsx, vsy);
  const double c = std::cos(phi_rad);
  const double s = std::sin(phi_rad);
  ModuleRates rates;
  rates.wheel_rate_radps = (c * vsx + s * vsy) / m.wheel_radius_m;
  rates.steer_rate_radps = (-s * vsx + c * vsy) / m.caster_offset_m - t.wz_radps;
  return rates;
}

void contact_point_velocity(const SwpcModuleParams& m, double phi_rad, double steer_rate_radps,
                            const Twist2& t, double& vx, double& vy) noexcept {
  // c = p - d u turns with the body (w) and with the steering (phi_dot), so
  // v_c = v_s - d (w + phi_dot) n.
  double vsx = 0.0;
  double vsy = 0.0;
  steering_axis_velocity(m, t, vsx, vsy);
  const double k = m.caster_offset_m * (t.wz_radps + steer_rate_radps);
  vx = vsx + k * std::sin(phi_rad);
  vy = vsy - k * std::cos(phi_rad);
}

ForwardResult forward(std::span<const SwpcModuleParams> modules, std::span<const double> phi_rad,
                      std::span<const double> steer_rate_radps,
                      std::span<const double> wheel_rate_radps) noexcept {
  ForwardResult result;
  const std::size_t n = modules.size();
  if (n < 2 || n > kMaxModules || phi_rad.size() != n || steer_rate_radps.size() != n ||
      wheel_rate_radps.size() != n) {
    return result;
  }

  // Two rows per module:  u . v_s = r psi_dot   and   n . v_s - d w = d phi_dot.
  const auto rows = static_cast<Eigen::Index>(2 * n);
  SystemMatrix a(rows, 3);
  SystemVector b(rows);
  for (std::size_t i = 0; i < n; ++i) {
    const SwpcModuleParams& m = modules[i];
    const double c = std::cos(phi_rad[i]);
    const double s = std::sin(phi_rad[i]);
    const auto k = static_cast<Eigen::Index>(2 * i);
    a.row(k) << c, s, m.x_m * s - m.y_m * c;
    b(k) = m.wheel_radius_m * wheel_rate_radps[i];
    a.row(k + 1) << -s, c, m.x_m * c + m.y_m * s - m.caster_offset_m;
    b(k + 1) = m.caster_offset_m * steer_rate_radps[i];
  }
  if (!a.allFinite() || !b.allFinite()) {
    return result;
  }

  // Normal equations on unit-norm columns: a 3x3 solve is several times cheaper than a QR
  // of the 2N x 3 system, and the scaling makes the rank decision independent of the
  // robot's size (the w column carries lever arms in metres). The condition limit keeps
  // the squared condition number of the normal matrix far from machine precision.
  const Eigen::Matrix3d ata = a.transpose() * a;
  const Eigen::Vector3d col_norm = ata.diagonal().cwiseSqrt();
  if (!(col_norm.minCoeff() > 0.0)) {
    return result;
  }
  const Eigen::Vector3d inv_norm = col_norm.cwiseInverse();
  const Eigen::Matrix3d scaled = inv_norm.asDiagonal() * ata * inv_norm.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(scaled, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d lambda = eigen.eigenvalues();  // increasing; cond(A)^2 = max / min
  if (!(lambda(0) * kMaxCondition * kMaxCondition > lambda(2))) {
    return result;
  }

  const Eigen::LDLT<Eigen::Matrix3d> ldlt(scaled);
  const Eigen::Vector3d x =
      inv_norm.cwiseProduct(ldlt.solve(inv_norm.cwiseProduct(a.transpose() * b)));
  if (!x.allFinite()) {
    return result;
  }
  const double residual_sq = (a * x - b).squaredNorm();

  result.twist.vx_mps = x(0);
  result.twist.vy_mps = x(1);
  result.twist.wz_radps = x(2);
  result.residual = std::sqrt(residual_sq / static_cast<double>(rows));
  result.ok = true;
  return result;
}

bool self_aligned_steer_angle(const SwpcModuleParams& m, const Twist2& t,
                              double& phi_rad) noexcept {
  if (!finite_twist(t)) {
    return false;
  }
  double vsx = 0.0;
  double vsy = 0.0;
  steering_axis_velocity(m, t, vsx, vsy);
  const double speed = std::hypot(vsx, vsy);
  const double lateral = m.caster_offset_m * t.wz_radps;
  if (!(speed > std::abs(lateral))) {
    return false;
  }
  // n . v_s = |v_s| sin(alpha - phi) = d w; the principal asin keeps u . v_s > 0 (trailing).
  phi_rad = std::atan2(vsy, vsx) - std::asin(lateral / speed);
  return std::isfinite(phi_rad);
}

double desaturation_scale(std::span<const ModuleRates> rates, double max_wheel_rate_radps,
                          double max_steer_rate_radps) noexcept {
  if (!(max_wheel_rate_radps > 0.0) || !(max_steer_rate_radps > 0.0)) {
    return 0.0;
  }
  double scale = 1.0;
  for (const ModuleRates& r : rates) {
    if (!std::isfinite(r.wheel_rate_radps) || !std::isfinite(r.steer_rate_radps)) {
      return 0.0;
    }
    // Written as products so that a zero rate never divides.
    if (std::abs(r.wheel_rate_radps) * scale > max_wheel_rate_radps) {
      scale = max_wheel_rate_radps / std::abs(r.wheel_rate_radps);
    }
    if (std::abs(r.steer_rate_radps) * scale > max_steer_rate_radps) {
      scale = max_steer_rate_radps / std::abs(r.steer_rate_radps);
    }
  }
  return scale;
}

double desaturation_scale(std::span<const SwpcModuleParams> modules,
                          std::span<const double> phi_rad, const Twist2& t,
                          double max_wheel_rate_radps, double max_steer_rate_radps) noexcept {
  if (phi_rad.size() != modules.size() || modules.size() > kMaxModules) {
    return 0.0;
  }
  std::array<ModuleRates, kMaxModules> rates{};
  for (std::size_t i = 0; i < modules.size(); ++i) {
    rates[i] = inverse_module(modules[i], phi_rad[i], t);
  }
  return desaturation_scale(std::span<const ModuleRates>(rates.data(), modules.size()),
                            max_wheel_rate_radps, max_steer_rate_radps);
}

double max_steering_axis_speed(std::span<const SwpcModuleParams> modules,
                               const Twist2& t) noexcept {
  double speed = 0.0;
  for (const SwpcModuleParams& m : modules) {
    double vsx = 0.0;
    double vsy = 0.0;
    steering_axis_velocity(m, t, vsx, vsy);
    speed = std::max(speed, std::hypot(vsx, vsy));
  }
  return speed;
}

Pose2 integrate_twist(const Twist2& t, double dt_s) noexcept {
  // Velocity at time s in the start frame is R(w s) v; integrating R over [0, dt] gives
  // [[S, -C], [C, S]] with S = sin(w dt)/w and C = (1 - cos(w dt))/w.
  const double dyaw = t.wz_radps * dt_s;
  double sin_term = 0.0;
  double cos_term = 0.0;
  if (std::abs(dyaw) < 1e-6) {
    // Series (truncation below 1e-24 relative) also covers w = 0.
    const double dyaw2 = dyaw * dyaw;
    sin_term = dt_s * (1.0 - dyaw2 / 6.0);
    cos_term = dt_s * dyaw * (0.5 - dyaw2 / 24.0);
  } else {
    // 1 - cos = 2 sin^2(dyaw/2) avoids cancellation for small angles.
    const double half_sin = std::sin(0.5 * dyaw);
    sin_term = std::sin(dyaw) / t.wz_radps;
    cos_term = 2.0 * half_sin * half_sin / t.wz_radps;
  }
  Pose2 delta;
  delta.x_m = sin_term * t.vx_mps - cos_term * t.vy_mps;
  delta.y_m = cos_term * t.vx_mps + sin_term * t.vy_mps;
  delta.yaw_rad = dyaw;
  return delta;
}

}  // namespace swivel::swpc
