// SPDX-License-Identifier: Apache-2.0
#pragma once
// Velocity, acceleration and jerk limits on a commanded body twist: what a robot's own
// motion controller enforces (the robot model's `limits:`). The daemon applies it on the
// real-time loop to every command source and to the controlled stop; the simulator and the
// model-gap replay apply it where the robot would. Real-time safe: no allocation, no
// exceptions, no I/O.

#include <limits>

#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::motion {

inline constexpr double kNoLimit = std::numeric_limits<double>::infinity();

/// Limits of one axis; infinite where none applies.
struct AxisLimits {
  double velocity = kNoLimit;
  double acceleration = kNoLimit;
  double jerk = kNoLimit;
};

/// Tracks a scalar setpoint within its limits. Without a jerk limit the value moves towards
/// the setpoint at up to the acceleration limit; with one, the acceleration itself ramps and
/// is brought back to zero in time to arrive at the setpoint without overshoot.
class AxisLimiter {
 public:
  explicit AxisLimiter(const AxisLimits& limits = {}) noexcept;

  /// Advances by `dt_s` towards `target` and returns the limited value. A non-positive or
  /// non-finite dt leaves the state as it is; a non-finite target counts as zero.
  double step(double target, double dt_s) noexcept;
  /// Sets the state (e.g. to the velocity the robot has when limiting starts).
  void reset(double value = 0.0, double acceleration = 0.0) noexcept;

  [[nodiscard]] double value() const noexcept { return value_; }
  [[nodiscard]] double acceleration() const noexcept { return acceleration_; }
  [[nodiscard]] const AxisLimits& limits() const noexcept { return limits_; }
  /// Whether any limit is finite.
  [[nodiscard]] bool active() const noexcept;

 private:
  AxisLimits limits_;
  double value_ = 0.0;
  double acceleration_ = 0.0;
};

/// The three axes of a body twist: x and y share the linear limits (each axis on its own,
/// as the robot model's `limits:` states them), wz takes the angular ones.
class TwistLimiter {
 public:
  TwistLimiter() noexcept = default;
  explicit TwistLimiter(const MotionLimits& limits) noexcept;

  /// Advances by `dt_s` towards `target` and returns the limited twist.
  Twist2 step(const Twist2& target, double dt_s) noexcept;
  void reset(const Twist2& current = {}) noexcept;
  /// Takes over `other`'s state (velocities and accelerations), so that switching between
  /// two sets of limits, e.g. from a command's to a controlled stop's, keeps the motion
  /// continuous.
  void continue_from(const TwistLimiter& other) noexcept;

  [[nodiscard]] Twist2 value() const noexcept;
  /// The axes on their own, e.g. to set one to the velocity the robot really got.
  AxisLimiter& x() noexcept { return x_; }
  AxisLimiter& y() noexcept { return y_; }
  AxisLimiter& wz() noexcept { return wz_; }
  /// Whether any limit applies (otherwise step() returns its target).
  [[nodiscard]] bool active() const noexcept;

  /// Axis limits of the linear and angular axes from a robot model's `limits:`.
  static AxisLimits linear_axis(const MotionLimits& limits) noexcept;
  static AxisLimits angular_axis(const MotionLimits& limits) noexcept;

 private:
  AxisLimiter x_;
  AxisLimiter y_;
  AxisLimiter wz_;
};

}  // namespace swivel::motion
