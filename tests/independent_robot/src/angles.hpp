// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cmath>
#include <numbers>

namespace swivel::independent {

/// The angle in (-pi, pi].
inline double wrap_angle(double a) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double w = std::fmod(a, kTwoPi);
  if (w > std::numbers::pi) w -= kTwoPi;
  if (w <= -std::numbers::pi) w += kTwoPi;
  return w;
}

/// The nearest encoder reading of an angle: a whole number of counts.
inline double quantize(double angle_rad, int counts_per_rev) {
  const double count = 2.0 * std::numbers::pi / counts_per_rev;
  const double q = std::round(angle_rad / count) * count;
  return q == 0.0 ? 0.0 : q;  // no "-0" in the log
}

}  // namespace swivel::independent
