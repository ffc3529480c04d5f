// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's mode and command-limiting stage: which twist the robot is asked for and how fast
// it may get there. The newest velocity command comes through a latest-value slot (a flood
// cannot hold the cycle, and the newest, e.g. a stop, always wins); a non-finite one is
// rejected (transient kNonFiniteCommand), one older than the timeout ends the motion
// (transient kCommandTimeout when it asked for motion). Every twist goes through one of two
// motion::TwistLimiters: the robot model's limits towards a command, the same with the
// controlled stop's deceleration whenever the loop itself stops the robot; a switch hands the
// state over, so that the twist stays continuous. The controlled stop before shutdown is
// requested from any thread and taken here: from then on no command moves the robot.
//
// push() is for the one command-source thread, request_stop() for any thread; everything
// else is for the loop thread. Real-time safe: no allocation, no lock, no I/O; noexcept.

#include <atomic>

#include "swivel/motion/twist_limiter.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/rt/latest_value.hpp"
#include "swivel/rt/loop_events.hpp"
#include "swivel/rt/state_snapshot.hpp"

namespace swivel::rt {

/// A cycle's time and the previous cycle's, if there was one.
struct CycleTime {
  double now_s = 0.0;
  bool has_last = false;
  double last_s = 0.0;
};

/// The limits of the stage.
struct CommandLimits {
  MotionLimits limits;  ///< the robot model's; absent ones are not applied
  /// The controlled stop's deceleration where `limits` has no acceleration limit (x and y,
  /// m/s^2; yaw, rad/s^2); infinite: zero at once.
  double stop_linear_deceleration_mps2 = 0.0;
  double stop_angular_deceleration_radps2 = 0.0;
  double command_timeout_s = 0.5;  ///< older commands stop the robot
  double period_s = 0.001;         ///< the loop's
};

class CommandStage {
 public:
  explicit CommandStage(const CommandLimits& limits) noexcept;
  ~CommandStage() = default;
  // It points into itself (the current limiter): neither copied nor moved.
  CommandStage(const CommandStage&) = delete;
  CommandStage& operator=(const CommandStage&) = delete;
  CommandStage(CommandStage&&) = delete;
  CommandStage& operator=(CommandStage&&) = delete;

  /// The command-source thread: the newest command, taken at the next cycle.
  void push(const VelocityCommand& command) noexcept { (void)commands_.publish(command); }

  /// Any thread: the controlled stop, asked for at `requested_s` (the loop's clock).
  void request_stop(double requested_s) noexcept;

  /// Loop thread, first in a cycle: takes a requested controlled stop.
  void take_stop_request(const CycleTime& time, LoopEvents& events) noexcept;

  /// Loop thread: takes the newest command (rejected when non-finite) and ends a timed-out one.
  void take_command(double now_s, LoopEvents& events) noexcept;

  /// Only a command that arrives from now on moves the robot.
  void drop() noexcept { has_command_ = false; }

  /// True when the command moves the robot this cycle: one is held, the loop is not stopping
  /// and nothing else (`held`: a calibration, the final cycle, a latched fault) holds it.
  [[nodiscard]] bool moving(bool held) const noexcept {
    return !held && !stopping_ && has_command_;
  }
  [[nodiscard]] const Twist2& command_twist() const noexcept { return command_.twist; }
  [[nodiscard]] bool stopping() const noexcept { return stopping_; }

  /// The limited twist towards `target` (`stopping`: the stop's limits).
  Twist2 limit(const Twist2& target, bool stopping, const CycleTime& time) noexcept;

  /// The drivetrain scaled `limited` down to `applied`: the limiter continues from there.
  void follow(const Twist2& limited, const Twist2& applied) noexcept;

  /// The limits start again from `applied` (what the robot was given).
  void reset(const Twist2& applied) noexcept { limiter_->reset(applied); }

  /// A new robot model's limits; both limiters start again from zero (the robot is at rest).
  void set_limits(const MotionLimits& limits) noexcept;

 private:
  LatestValue<VelocityCommand> commands_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<double> stop_requested_s_{0.0};  // written before the flag
  static_assert(std::atomic<double>::is_always_lock_free);

  CommandLimits limits_;
  VelocityCommand command_{};
  bool has_command_ = false;
  bool stopping_ = false;                 // the controlled stop was taken
  double stop_catch_up_s_ = 0.0;          // extra time for the stop's first step (limit())
  motion::TwistLimiter command_limiter_;  // the robot model's limits
  motion::TwistLimiter stop_limiter_;     // the same, with the stop deceleration
  motion::TwistLimiter* limiter_ = &stop_limiter_;  // the one whose state is current
};

}  // namespace swivel::rt
