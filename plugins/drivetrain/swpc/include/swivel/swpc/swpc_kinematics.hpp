// SPDX-License-Identifier: Apache-2.0
#pragma once
// Kinematics of a robot on N single-wheel powered casters (docs/methods.md §1).
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
/// @pre caster_offset_m > 0 and wheel_radius_m > 0 (the rates are divided by them).
ModuleRates inverse_module(const SwpcModuleParams& m, double phi_rad, const Twist2& t) noexcept;

/// Velocity of the wheel contact point (robot frame) given the body twist, the steering
/// angle and steering rate; along n it is zero when the rates come from inverse_module.
void contact_point_velocity(const SwpcModuleParams& m, double phi_rad, double steer_rate_radps,
                            const Twist2& t, double& vx, double& vy) noexcept;

/// Largest condition number (of the 2N x 3 matrix with unit-norm columns) forward() accepts.
inline constexpr double kMaxCondition = 1e4;

struct ForwardResult {
  Twist2 twist;
  double residual = 0.0;  ///< RMS of the 2N equation residuals, m/s (slip indicator)
  bool ok = false;        ///< false when the system is degenerate (N < 2 or rank < 3)
};

/// Forward kinematics: body twist from all modules' true steering angles, steering rates
/// and wheel rates by least squares over the 2N equations
///   u_i . v_s,i = r_i psi_dot_i   and   n_i . v_s,i = d_i (phi_dot_i + w).
/// All spans have the same size N (2 <= N <= kMaxModules).
/// `ok` is false when N or the span sizes are out of range, an input is not finite, or the
/// system does not determine the twist (rank < 3, judged on the column-scaled matrix with a
/// condition limit of kMaxCondition): e.g. every module at one point with d = 0, or every
/// module at one point with the same steering angle. With d > 0, co-located modules at
/// different steering angles do determine w (through the steering rates), so they are ok.
/// Real-time safe: noexcept, no allocation (fixed-capacity Eigen storage).
ForwardResult forward(std::span<const SwpcModuleParams> modules, std::span<const double> phi_rad,
                      std::span<const double> steer_rate_radps,
                      std::span<const double> wheel_rate_radps) noexcept;

/// Steering angle (true, rad) at which a free caster is self-aligned for body twist `t`:
/// the steady state phi_dot = 0 with the wheel rolling forward, i.e. n . v_s = d w and
/// u . v_s > 0, phi = atan2(v_s) - asin(d w / |v_s|). For w = 0 this is the heading of the
/// steering-axis velocity. Returns false (phi_rad untouched) when no steady state exists:
/// |v_s| <= d |w| (the axis lies within d of the instantaneous centre of rotation, so the
/// caster keeps turning) or the inputs are not finite.
bool self_aligned_steer_angle(const SwpcModuleParams& m, const Twist2& t, double& phi_rad) noexcept;

/// Largest factor s in [0, 1] such that the rates of s * `t` (inverse kinematics at the
/// given true steering angles) satisfy |wheel rate| <= max_wheel_rate_radps and
/// |steer rate| <= max_steer_rate_radps for every module. Both rates are linear in the
/// twist at fixed phi, so s = min(1, min over modules of limit / |rate|). Returns 0 for a
/// non-finite rate or a non-positive limit. Same span sizes as forward().
double desaturation_scale(std::span<const SwpcModuleParams> modules,
                          std::span<const double> phi_rad, const Twist2& t,
                          double max_wheel_rate_radps, double max_steer_rate_radps) noexcept;

/// The same factor from rates already computed for the unscaled twist (each module's
/// inverse_module at its angle): lets a caller evaluate the inverse kinematics once and
/// scale the rates. Returns 0 for a non-finite rate or a non-positive limit.
double desaturation_scale(std::span<const ModuleRates> rates, double max_wheel_rate_radps,
                          double max_steer_rate_radps) noexcept;

/// Largest steering-axis speed over all modules for body twist `t`, m/s (a measure of how
/// fast the robot moves anywhere on its footprint, rotation included).
double max_steering_axis_speed(std::span<const SwpcModuleParams> modules, const Twist2& t) noexcept;

/// Motion over `dt_s` under constant body twist `t`, in the robot frame at the start of the
/// step (exact arc integration; a series expansion for small rotations).
Pose2 integrate_twist(const Twist2& t, double dt_s) noexcept;

}  // namespace swivel::swpc
