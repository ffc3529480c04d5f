// SPDX-License-Identifier: Apache-2.0
#pragma once
// Differential-drive kinematics (docs/methods.md §2, eq. (1)-(4)), written for this generator
// alone: the robot's controller uses the inverse with the nominal geometry, the true robot
// moves by the forward with the true one.

#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

struct DifferentialGeometry {
  double wheel_radius_left_m = 0.075;
  double wheel_radius_right_m = 0.075;
  double track_width_m = 0.40;
};

/// Wheel angular rates (rad/s, forward positive).
struct WheelPairRates {
  double left_radps = 0.0;
  double right_radps = 0.0;
};

/// Wheel rates that give forward speed v and yaw rate w: (v -+ w b / 2) / r.
WheelPairRates differential_inverse(const DifferentialGeometry& g, double v_mps, double w_radps);

/// Body twist from the wheels' ground speeds (m/s): v = (v_R + v_L) / 2, w = (v_R - v_L) / b.
Twist differential_forward(double left_ground_mps, double right_ground_mps, double track_width_m);

}  // namespace swivel::independent
