// SPDX-License-Identifier: Apache-2.0
#pragma once
// The checks the loop's stages run on what crosses a plugin boundary: all finite, all zero.
// Plain arithmetic, real-time safe.

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "swivel/types.hpp"

namespace swivel::rt {

inline bool finite(double v) noexcept { return std::isfinite(v); }

inline bool finite(const Twist2& t) noexcept {
  return finite(t.vx_mps) && finite(t.vy_mps) && finite(t.wz_radps);
}

inline bool finite(const Pose2& p) noexcept {
  return finite(p.x_m) && finite(p.y_m) && finite(p.yaw_rad);
}

inline bool finite(const MotionCaptureSample& m) noexcept {
  return finite(m.stamp_s) && finite(m.pose);
}

inline bool finite(const ActuatorCommand& c) noexcept {
  for (std::uint32_t i = 0; i < c.module_count; ++i) {
    if (!finite(c.wheel_rate_radps[i]) || !finite(c.steer_rate_radps[i])) return false;
  }
  return true;
}

/// True when the estimate has no covariance or a finite one.
inline bool finite_covariance(const PoseEstimate& e) noexcept {
  return !e.has_covariance ||
         std::all_of(e.covariance.begin(), e.covariance.end(), [](double v) { return finite(v); });
}

inline bool is_zero(const Twist2& t) noexcept {
  return t.vx_mps == 0.0 && t.vy_mps == 0.0 && t.wz_radps == 0.0;
}

/// True when every wheel and steering setpoint is zero.
inline bool all_zero(const ActuatorCommand& c) noexcept {
  for (std::uint32_t i = 0; i < c.module_count && i < kMaxModules; ++i) {
    if (c.wheel_rate_radps[i] != 0.0 || c.steer_rate_radps[i] != 0.0) return false;
  }
  return true;
}

}  // namespace swivel::rt
