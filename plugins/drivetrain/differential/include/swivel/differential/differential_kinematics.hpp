// SPDX-License-Identifier: Apache-2.0
#pragma once
// Kinematics of the differential-drive (docent) robot, docs/methods.md §2 eq. (1)-(6).
// Plain maths: no threads, no YAML. Real-time safe (no allocation, noexcept).

#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::differential {

struct WheelRates {
  double left_radps = 0.0;
  double right_radps = 0.0;
};

/// Wheel rates that produce forward speed `vx_mps` and yaw rate `wz_radps`.
WheelRates inverse(const DifferentialParams& p, double vx_mps, double wz_radps) noexcept;

/// Body twist (vy = 0) from wheel rates.
Twist2 forward(const DifferentialParams& p, const WheelRates& rates) noexcept;

/// Motion over one step in the robot frame at the start of the step, from wheel angle
/// increments (rad): d = (dR + dL)/2, dyaw = (dR - dL)/b, integrated along the arc.
Pose2 forward_increment(const DifferentialParams& p, double dpsi_left_rad,
                        double dpsi_right_rad) noexcept;

/// Factor in (0, 1] by which (vx, wz) must both be scaled so that neither wheel exceeds
/// `max_wheel_rate_radps`; scaling both keeps the path curvature wz/vx. 1 when within
/// limits, 0 when the limit is not positive. Real-time safe.
double wheel_limit_scale(const DifferentialParams& p, double vx_mps, double wz_radps,
                         double max_wheel_rate_radps) noexcept;

}  // namespace swivel::differential
