// SPDX-License-Identifier: Apache-2.0
#pragma once
// Open-loop driving of a simulated robot: a controller that turns body twists into actuator
// setpoints with the NOMINAL model's inverse kinematics (the drivetrain libraries), the
// calibration motion of docs/methods.md §1, and the start-up alignment of a world's casters.
// Used by `swivel-lab simulate` and by the model-gap replay, so that both drive the world
// the same way.

#include <array>
#include <cstddef>
#include <string>

#include "swivel/robot_model.hpp"
#include "swivel/run_log.hpp"
#include "swivel/sim/effects.hpp"
#include "swivel/types.hpp"

namespace swivel::sim {

/// The calibration motion: module `locked_module` (0-based) locked at measured steering
/// angle `locked_steer_meas_rad`; the others steer freely with constant wheel rates chosen
/// (with the nominal geometry) to turn the robot at `yaw_rate_radps` about the locked
/// wheel's contact point.
struct CalibrationMotion {
  std::size_t locked_module = 0;
  double locked_steer_meas_rad = 0.0;
  double yaw_rate_radps = 0.3;
};

class OpenLoopController {
 public:
  /// Uses the nominal model's geometry and its `limits:`.
  /// @throws std::invalid_argument for a model without valid geometry.
  explicit OpenLoopController(const RobotModel& nominal);
  /// The nominal geometry with other limits (the robot's own, when they differ from what the
  /// nominal model states).
  OpenLoopController(RobotModel nominal, const MotionLimits& limits);

  /// Real-time safe. Setpoints for body twist `twist` given the current readings: wheel
  /// rates (differential; vy is ignored) or every module's wheel and steering rate at its
  /// measured steering angle plus the nominal offset (swpc), all in kVelocity mode; steering
  /// rates clamped to the steering rate limit. The twist's own limits (velocity,
  /// acceleration, jerk) need state: the caller applies them with a motion::TwistLimiter.
  void velocity(const Twist2& twist, const HardwareState& measured,
                ActuatorCommand& out) const noexcept;

  /// Real-time safe. Setpoints of the calibration motion (swpc only) and the body twist
  /// they command under the nominal model. Returns false when `motion` is invalid (not an
  /// swpc robot, module out of range) or a free caster has no steady state (its steering
  /// axis within its caster offset of the pivot); `out` then commands zero rates with the
  /// module locked.
  bool calibration(const CalibrationMotion& motion, ActuatorCommand& out,
                   Twist2& commanded) const noexcept;

  [[nodiscard]] const RobotModel& nominal() const noexcept { return nominal_; }

 private:
  RobotModel nominal_;
  double max_steer_rate_radps_ = 0.0;  // 0: no limit
};

/// True steering angles at which a world's casters start so that they already trail the
/// first motion `twist` (rad, true angles; zero where a caster has no steady state).
/// Differential robots: all zero.
std::array<double, kMaxModules> aligned_steer_angles(const PlantParams& plant,
                                                     const Twist2& twist) noexcept;

/// True steering angles at the start of the calibration motion: the locked module at its
/// measured angle plus its true offset, the free casters self-aligned for the rotation
/// about the true pivot (as the paper aligns them before each run).
std::array<double, kMaxModules> calibration_steer_angles(const PlantParams& plant,
                                                         const CalibrationMotion& motion) noexcept;

/// A run-log row from one reading and the twist commanded at its time (run_log.hpp).
RunLogSample make_run_log_sample(const HardwareState& reading, const Twist2& commanded) noexcept;

}  // namespace swivel::sim
