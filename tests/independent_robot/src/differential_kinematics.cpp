// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/differential_kinematics.hpp"

namespace swivel::independent {

WheelPairRates differential_inverse(const DifferentialGeometry& g, double v_mps, double w_radps) {
  const double half_turn = 0.5 * w_radps * g.track_width_m;
  return WheelPairRates{(v_mps - half_turn) / g.wheel_radius_left_m,
                        (v_mps + half_turn) / g.wheel_radius_right_m};
}

Twist differential_forward(double left_ground_mps, double right_ground_mps, double track_width_m) {
  return Twist{0.5 * (right_ground_mps + left_ground_mps), 0.0,
               (right_ground_mps - left_ground_mps) / track_width_m};
}

}  // namespace swivel::independent
