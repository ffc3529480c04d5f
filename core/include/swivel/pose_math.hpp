// SPDX-License-Identifier: Apache-2.0
#pragma once
// Planar rigid-body helpers on Pose2 (types.hpp): composition, inverse, relative pose,
// angle wrapping and degree conversion. Header-only, noexcept, allocation-free.

#include <cmath>
#include <numbers>

#include "swivel/types.hpp"

namespace swivel {

/// Radians in a degree, and degrees in a radian (for people-facing options and reports).
inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;
inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;

/// The angle in (-pi, pi].
inline double wrap_pi(double angle_rad) noexcept {
  const double a = std::remainder(angle_rad, 2.0 * std::numbers::pi);
  return a <= -std::numbers::pi ? a + 2.0 * std::numbers::pi : a;
}

/// a then b: b is expressed in a's frame. The heading is not wrapped, so unwrapped
/// headings stay unwrapped.
inline Pose2 compose(const Pose2& a, const Pose2& b) noexcept {
  const double c = std::cos(a.yaw_rad);
  const double s = std::sin(a.yaw_rad);
  return Pose2{a.x_m + c * b.x_m - s * b.y_m, a.y_m + s * b.x_m + c * b.y_m, a.yaw_rad + b.yaw_rad};
}

/// The pose p^-1 (compose(p, inverse(p)) is the identity).
inline Pose2 inverse(const Pose2& p) noexcept {
  const double c = std::cos(p.yaw_rad);
  const double s = std::sin(p.yaw_rad);
  return Pose2{-c * p.x_m - s * p.y_m, s * p.x_m - c * p.y_m, -p.yaw_rad};
}

/// b seen from a: a^-1 b, in a's frame (heading difference not wrapped).
inline Pose2 between(const Pose2& a, const Pose2& b) noexcept { return compose(inverse(a), b); }

/// Linear interpolation of position and (unwrapped) heading: a at f = 0, b at f = 1.
inline Pose2 lerp(const Pose2& a, const Pose2& b, double f) noexcept {
  return Pose2{a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m),
               a.yaw_rad + f * (b.yaw_rad - a.yaw_rad)};
}

}  // namespace swivel
