#pragma once
// Kinematics of a robot on N single-wheel powered casters (PAPERS.md §1).
// Conventions: steering-axis velocity v_s = (vx - w y_i, vy + w x_i); wheel heading
// u = (cos phi, sin phi), normal n = (-sin phi, cos phi); contact c = p - d u (trailing);
// rolling r psi_dot = u . v_s; no lateral slip phi_dot = (n . v_s)/d - w. phi here is the
// TRUE steering angle; measured = true - steering_offset.
// Plain maths: no threads, no YAML. Everything is noexcept and allocation-free.

#include <cstdint>
#include <span>

#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::swpc {

struct ModuleRates {
  double wheel_rate_radps = 0.0;  ///< psi_dot
  double steer_rate_radps = 0.0;  ///< phi_dot
};

/// Velocity of the steering axis of module `m` for body twist `t` (robot frame).
void steering_axis_velocity(const SwpcModuleParams& m, const Twist2& t, double& vx,
                            double& vy) noexcept;

/// Inverse kinematics of one module at true steering angle `phi_rad`.
ModuleRates inverse_module(const SwpcModuleParams& m, double phi_rad, const Twist2& t) noexcept;

/// Velocity of the wheel contact point (robot frame) given the body twist, the steering
/// angle and steering rate; along n it is zero when the rates come from inverse_module.
void contact_point_velocity(const SwpcModuleParams& m, double phi_rad, double steer_rate_radps,
                            const Twist2& t, double& vx, double& vy) noexcept;

struct ForwardResult {
  Twist2 twist;
  double residual = 0.0;  ///< RMS of the 2N equation residuals, m/s (slip indicator)
  bool ok = false;        ///< false when the system is degenerate (N < 2 or rank < 3)
};

/// Forward kinematics: body twist from all modules' true steering angles, steering rates
/// and wheel rates by least squares over the 2N equations
///   u_i . v_s,i = r_i psi_dot_i   and   n_i . v_s,i = d_i (phi_dot_i + w).
/// All spans have the same size N (2 <= N <= kMaxModules).
ForwardResult forward(std::span<const SwpcModuleParams> modules, std::span<const double> phi_rad,
                      std::span<const double> steer_rate_radps,
                      std::span<const double> wheel_rate_radps) noexcept;

}  // namespace swivel::swpc
