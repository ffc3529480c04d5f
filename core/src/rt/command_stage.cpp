// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/command_stage.hpp"

#include <algorithm>
#include <cmath>

#include "swivel/rt/finite.hpp"

namespace swivel::rt {
namespace {

// The controlled stop: the model's limits, with the stop's deceleration on the axes whose
// model has no acceleration limit.
MotionLimits controlled_stop_limits(const CommandLimits& limits) noexcept {
  MotionLimits stop = limits.limits;
  if (!stop.linear_acceleration_mps2) {
    stop.linear_acceleration_mps2 = limits.stop_linear_deceleration_mps2;
  }
  if (!stop.angular_acceleration_radps2) {
    stop.angular_acceleration_radps2 = limits.stop_angular_deceleration_radps2;
  }
  return stop;
}

// Below these a drivetrain may fade a small twist out on purpose (swpc near standstill).
constexpr double kFollowFloorMps = 0.02;
constexpr double kFollowFloorRadps = 0.02;

}  // namespace

CommandStage::CommandStage(const CommandLimits& limits) noexcept
    : limits_(limits),
      command_limiter_(limits.limits),
      stop_limiter_(controlled_stop_limits(limits)) {}

void CommandStage::request_stop(double requested_s) noexcept {
  bool expected = false;
  if (stop_requested_.load(std::memory_order_acquire)) return;
  stop_requested_s_.store(requested_s, std::memory_order_relaxed);
  (void)stop_requested_.compare_exchange_strong(expected, true, std::memory_order_acq_rel);
}

void CommandStage::take_stop_request(const CycleTime& time, LoopEvents& events) noexcept {
  if (stopping_ || !stop_requested_.load(std::memory_order_acquire)) return;
  stopping_ = true;
  // The setpoint about to be written holds for a period, and the last one has held since the
  // request: the first step decelerates for both, so that the stop brakes as if it had begun
  // at the request and each setpoint were the ramp's value mid-period.
  const double now_s = time.now_s;
  const double since_request_s = now_s - stop_requested_s_.load(std::memory_order_relaxed);
  stop_catch_up_s_ = std::max(since_request_s, 0.0) + 0.5 * limits_.period_s -
                     (time.has_last ? std::max(now_s - time.last_s, 0.0) : limits_.period_s);
  events.log(LogLevel::kInfo, LogCode::kMessage, now_s,
             "controlled stop: commands ignored, bringing the robot to rest");
}

void CommandStage::take_command(double now_s, LoopEvents& events) noexcept {
  // One per cycle at most: the slot keeps only the newest.
  VelocityCommand incoming;
  if (commands_.take(incoming) && !stopping_) {
    if (finite(incoming.twist) && finite(incoming.received_s)) {
      command_ = incoming;
      has_command_ = true;
      events.clear_transient();
    } else {
      has_command_ = false;
      events.raise_transient(FaultCode::kNonFiniteCommand, now_s, "non-finite command rejected");
      events.log(LogLevel::kWarn, LogCode::kCommandRejected, now_s, "non-finite velocity command",
                 static_cast<double>(incoming.sequence));
    }
  }
  if (stopping_) has_command_ = false;  // shutting down: no command moves the robot again
  if (has_command_ && now_s - command_.received_s > limits_.command_timeout_s) {
    has_command_ = false;
    // A stream whose last word was a stop (Nav2 after every goal, a teleop released) has
    // simply ended: the robot is idle, not faulty. Only one that went silent mid-motion is.
    if (!is_zero(command_.twist)) {
      events.raise_transient(FaultCode::kCommandTimeout, now_s, "velocity command timed out");
    }
  }
}

Twist2 CommandStage::limit(const Twist2& target, bool stopping, const CycleTime& time) noexcept {
  motion::TwistLimiter& limiter = stopping ? stop_limiter_ : command_limiter_;
  if (&limiter != limiter_) {
    limiter.continue_from(*limiter_);
    limiter_ = &limiter;
  }
  if (!limiter.active()) {
    limiter.reset(target);
    return target;
  }
  // The time that really passed, so that a late cycle does not stretch a stop. Towards a
  // command it is bounded, so that a stalled loop does not make the twist jump up; a stop
  // only ever moves towards zero, so it takes all of it.
  const double period_s = limits_.period_s;
  double dt_s = period_s;
  if (time.has_last && time.now_s > time.last_s) {
    const double elapsed_s = time.now_s - time.last_s;
    dt_s = stopping ? elapsed_s : std::min(elapsed_s, 10.0 * period_s);
  }
  if (stopping && stop_catch_up_s_ != 0.0) {
    dt_s = std::max(dt_s + stop_catch_up_s_, 0.0);
    stop_catch_up_s_ = 0.0;
  }
  return limiter.step(target, dt_s);
}

// The drivetrain scaled the twist down to its own wheel or steering limits: the limiter
// continues from what the robot was commanded, so that a later stop ramps down from the
// robot's speed and not from one it never reached. Below the floors a drivetrain may fade a
// small twist out on purpose; following it there would keep the robot from ever starting.
void CommandStage::follow(const Twist2& limited, const Twist2& applied) noexcept {
  const auto follow_axis = [](motion::AxisLimiter& axis, double wanted, double got, double floor) {
    if (std::abs(wanted) >= floor && std::abs(got) < std::abs(wanted) * (1.0 - 1e-9)) {
      axis.reset(got);
    }
  };
  follow_axis(limiter_->x(), limited.vx_mps, applied.vx_mps, kFollowFloorMps);
  follow_axis(limiter_->y(), limited.vy_mps, applied.vy_mps, kFollowFloorMps);
  follow_axis(limiter_->wz(), limited.wz_radps, applied.wz_radps, kFollowFloorRadps);
}

void CommandStage::set_limits(const MotionLimits& limits) noexcept {
  limits_.limits = limits;
  command_limiter_ = motion::TwistLimiter(limits_.limits);
  stop_limiter_ = motion::TwistLimiter(controlled_stop_limits(limits_));
  command_limiter_.reset();
  stop_limiter_.reset();
  limiter_ = &stop_limiter_;
}

}  // namespace swivel::rt
