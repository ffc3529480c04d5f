// SPDX-License-Identifier: Apache-2.0
#pragma once
// Caster robots whose steering servos and tyres push against each other (swpc, every module
// steered by its servo). A kinematic world turns each caster exactly as its servo is told and
// moves the body as the wheels' least squares say; a real caster is held by its tyre, and its
// servo turns it only as far as the servo's torque can drag the tyre across the floor. Where
// the robot's controller steers by a geometry or angles the robot does not have, its servos
// wind up against their tyres, and the casters stay behind their references by as much as the
// tyres' friction holds (a servo's yield).
//
// One implicit step of length h balances, for the body twist (vx, vy, w) and every caster's
// steering rate:
//  - each tyre's force, from its slip (the contact point's velocity against its wheel's
//    rolling, over the contact's speed or a creep floor), proportional to it while it grips
//    and capped by friction, f / sqrt(1 + |f|^2) in units of the tyre's friction mu N;
//  - the body's inertia, with every wheel carrying the same load;
//  - each caster's servo, its torque over Kp being e + tau (reference rate - rate), e the
//    servo's error (reference minus angle) at the step's end, against the tyre's lateral force
//    at the caster offset: (e + tau (reference rate - rate)) = yield * f_lateral, the yield
//    being d mu N / Kp.
// Casters have no inertia of their own. Forces are in units of one tyre's friction, so the
// yield is the one figure of the servos and tyres a run must fix; the rest are fixed below.

#include <cstddef>
#include <span>

#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::sim {

/// The servos' and tyres' figures. With steering_yield_rad = 0 the servos are rigid and the
/// world is kinematic (this model is not used).
struct CasterForces {
  /// The servo error whose torque equals the tyre's friction at the caster offset,
  /// d mu N / Kp, rad.
  double steering_yield_rad = 0.0;
  /// The servo's damping over its stiffness, Kd / Kp, s.
  double servo_damping_s = 0.02;
  /// Tyre force per unit slip (slip velocity over the contact's speed), in units of its
  /// friction: a tyre that grips until it slides.
  double creep_stiffness = 1000.0;
  /// Slip is measured against the contact's speed or this, whichever is larger, m/s.
  double creep_floor_mps = 0.02;
  /// Friction coefficient of the tyres, for the body's inertia against their forces only.
  double friction_coefficient = 0.8;
};

/// One caster at the start of a step.
struct CasterState {
  double phi_rad = 0.0;           ///< true steering angle
  double servo_ref_rad = 0.0;     ///< the servo's reference angle
  double servo_rate_radps = 0.0;  ///< its rate over the step (the setpoint, after any lag)
  double wheel_rate_radps = 0.0;  ///< the wheel's rate over the step (its ground rate)
};

/// Solves one step of length `h_s`: the body twist (robot frame) and each caster's steering
/// rate. `previous_twist` is the last step's (the body's inertia carries it on); `twist` and
/// `steer_rate_radps` hold on entry where the iteration starts. Real-time safe (no
/// allocation). False when the iteration did not converge; the outputs are then its last
/// iterate.
[[nodiscard]] bool caster_force_step(const CasterForces& model,
                                     std::span<const SwpcModuleParams> modules,
                                     std::span<const CasterState> casters, double h_s,
                                     const Twist2& previous_twist, Twist2& twist,
                                     std::span<double> steer_rate_radps) noexcept;

/// Throws std::invalid_argument naming the figure that is not finite and >= 0 (the yield) or
/// positive (the others).
void validate_caster_forces(const CasterForces& model);

}  // namespace swivel::sim
