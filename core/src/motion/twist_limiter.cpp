// SPDX-License-Identifier: Apache-2.0
#include "swivel/motion/twist_limiter.hpp"

#include <algorithm>
#include <cmath>

namespace swivel::motion {
namespace {

double clamp_abs(double v, double limit) noexcept { return std::clamp(v, -limit, limit); }

double limit_or_none(const std::optional<double>& v) noexcept {
  if (v && std::isfinite(*v) && *v > 0.0) return *v;
  return kNoLimit;
}

}  // namespace

AxisLimiter::AxisLimiter(const AxisLimits& limits) noexcept : limits_(limits) {}

bool AxisLimiter::active() const noexcept {
  return std::isfinite(limits_.velocity) || std::isfinite(limits_.acceleration) ||
         std::isfinite(limits_.jerk);
}

void AxisLimiter::reset(double value, double acceleration) noexcept {
  value_ = std::isfinite(value) ? value : 0.0;
  acceleration_ = std::isfinite(acceleration) ? acceleration : 0.0;
}

double AxisLimiter::step(double target, double dt_s) noexcept {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return value_;
  if (!std::isfinite(target)) target = 0.0;
  target = clamp_abs(target, limits_.velocity);
  const double error = target - value_;
  const double a_max = limits_.acceleration;
  const double j_max = limits_.jerk;
  double a = 0.0;
  if (!std::isfinite(j_max)) {
    a = clamp_abs(error / dt_s, a_max);
  } else {
    // The acceleration from which ramping it down at j_max, one step at a time, ends exactly
    // at the target: a^2 / (2 j) + a dt / 2 of velocity change remains while it falls to zero.
    const double half_step = 0.5 * j_max * dt_s;
    const double braking =
        std::sqrt(half_step * half_step + 2.0 * j_max * std::abs(error)) - half_step;
    const double wanted = std::copysign(std::min(a_max, braking), error);
    a = acceleration_ + clamp_abs(wanted - acceleration_, j_max * dt_s);
    // Within one step of the target: arrive instead of oscillating about it.
    if (std::abs(error) <= std::abs(a) * dt_s && std::abs(error / dt_s) <= a_max &&
        std::abs(error / dt_s - acceleration_) <= j_max * dt_s) {
      a = error / dt_s;
    }
  }
  value_ += a * dt_s;
  acceleration_ = a;
  if (value_ == target) acceleration_ = 0.0;
  return value_;
}

AxisLimits TwistLimiter::linear_axis(const MotionLimits& limits) noexcept {
  return {limit_or_none(limits.linear_velocity_mps), limit_or_none(limits.linear_acceleration_mps2),
          limit_or_none(limits.linear_jerk_mps3)};
}

AxisLimits TwistLimiter::angular_axis(const MotionLimits& limits) noexcept {
  return {limit_or_none(limits.angular_velocity_radps),
          limit_or_none(limits.angular_acceleration_radps2),
          limit_or_none(limits.angular_jerk_radps3)};
}

TwistLimiter::TwistLimiter(const MotionLimits& limits) noexcept
    : x_(linear_axis(limits)), y_(linear_axis(limits)), wz_(angular_axis(limits)) {}

Twist2 TwistLimiter::step(const Twist2& target, double dt_s) noexcept {
  return Twist2{x_.step(target.vx_mps, dt_s), y_.step(target.vy_mps, dt_s),
                wz_.step(target.wz_radps, dt_s)};
}

void TwistLimiter::reset(const Twist2& current) noexcept {
  x_.reset(current.vx_mps);
  y_.reset(current.vy_mps);
  wz_.reset(current.wz_radps);
}

void TwistLimiter::continue_from(const TwistLimiter& other) noexcept {
  x_.reset(other.x_.value(), other.x_.acceleration());
  y_.reset(other.y_.value(), other.y_.acceleration());
  wz_.reset(other.wz_.value(), other.wz_.acceleration());
}

Twist2 TwistLimiter::value() const noexcept { return Twist2{x_.value(), y_.value(), wz_.value()}; }

bool TwistLimiter::active() const noexcept { return x_.active() || wz_.active(); }

}  // namespace swivel::motion
