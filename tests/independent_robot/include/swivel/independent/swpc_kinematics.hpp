// SPDX-License-Identifier: Apache-2.0
#pragma once
// Kinematics of single-wheel powered casters (docs/methods.md §1), written for this generator
// alone. Conventions: steering-axis velocity v_s = (vx - w y, vy + w x); wheel heading
// u = (cos phi, sin phi), normal n = (-sin phi, cos phi); the contact point trails the axis,
// c = p - d u; rolling r psi_dot = u . v_s; no lateral slip phi_dot = (n . v_s) / d - w.
// phi is the true steering angle here; measured = true - steering offset.

#include <span>

#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

struct SwpcModule {
  double x_m = 0.0;  ///< steering axis, robot frame
  double y_m = 0.0;
  double steering_offset_rad = 0.0;  ///< true steering = measured + offset
  double caster_offset_m = 0.020;    ///< d
  double wheel_radius_m = 0.055;     ///< r
};

struct ModuleRates {
  double wheel_radps = 0.0;  ///< psi_dot
  double steer_radps = 0.0;  ///< phi_dot
};

/// The wheel and steering rates that make module `m`, at true steering angle `phi_rad`,
/// follow the body twist `body` without slipping.
ModuleRates swpc_inverse(const SwpcModule& m, double phi_rad, const Twist& body);

/// The steering rate a passive (self-aligning) caster takes: the no-lateral-slip law.
double swpc_passive_steer_rate(const SwpcModule& m, double phi_rad, const Twist& body);

/// Forward kinematics: the body twist that best satisfies, in least squares, the rolling
/// and the no-lateral-slip equation of every module (2N equations, 3 unknowns), given each
/// contact's rolling speed (m/s, r psi_dot with any slip) and steering rate.
/// @pre all spans have the same size, at least 2.
Twist swpc_forward(std::span<const SwpcModule> modules, std::span<const double> phi_rad,
                   std::span<const double> rolling_speed_mps,
                   std::span<const double> steer_rate_radps);

/// The body twist of passive casters: the rolling equations alone (N equations). They leave
/// a direction free when the casters are parallel (across the wheels) or when their heading
/// lines meet in one point; nothing in the equations decides the motion there. The solve
/// minimises |A z - b|^2 + weight |z - z_prior|^2 (z = (vx, vy, w 0.25 m)): in a free
/// direction the body does what `prior` does, elsewhere the pull changes the answer by about
/// weight / e of the difference (e about 1 per module in a determined direction).
Twist swpc_forward_rolling(std::span<const SwpcModule> modules, std::span<const double> phi_rad,
                           std::span<const double> rolling_speed_mps, const Twist& prior,
                           double weight);

}  // namespace swivel::independent
