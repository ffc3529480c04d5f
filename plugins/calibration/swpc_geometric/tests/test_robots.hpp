// SPDX-License-Identifier: Apache-2.0
#pragma once
// Random robots for the calibration tests: N modules spread around a circle, parameters
// perturbed like the paper's Monte Carlo.

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "swivel/robot_model.hpp"

namespace swivel::calibration::test {

inline std::vector<SwpcModuleParams> random_robot(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> rel(0.7, 1.3);
  std::uniform_real_distribution<double> offset(-0.5236, 0.5236);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<SwpcModuleParams> modules(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double angle = 2.0 * std::numbers::pi * (static_cast<double>(i) + 0.5 + jitter(rng)) /
                         static_cast<double>(n);
    const double radius = 0.25 * rel(rng);
    modules[i].x_m = radius * std::cos(angle);
    modules[i].y_m = radius * std::sin(angle);
    modules[i].steering_offset_rad = offset(rng);
    modules[i].caster_offset_m = 0.020 * rel(rng);
    modules[i].wheel_radius_m = 0.055 * rel(rng);
  }
  return modules;
}

}  // namespace swivel::calibration::test
