// SPDX-License-Identifier: Apache-2.0
// How hard a caster robot's steering servos press against their tyres while it drives
// (README.md, "What a run can show").
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "swivel/second/second_robot.hpp"

namespace swivel::second {

std::vector<double> driving_servo_errors_rad(const std::vector<Row>& rows) {
  const std::size_t casters = rows.empty() ? 0 : rows.front().steering_servo_error_rad.size();
  std::vector<double> out(casters, 0.0);
  std::vector<double> driving;
  driving.reserve(rows.size());
  for (std::size_t i = 0; i < casters; ++i) {
    driving.clear();
    for (const Row& r : rows) {
      if (std::hypot(r.twist[0], r.twist[1]) > kDrivingSpeedMps)
        driving.push_back(std::abs(r.steering_servo_error_rad[i]));
    }
    if (driving.empty()) continue;
    const auto mid = driving.begin() + static_cast<std::ptrdiff_t>(driving.size() / 2);
    std::nth_element(driving.begin(), mid, driving.end());
    out[i] = *mid;
  }
  return out;
}

double largest_driving_servo_error_rad(const std::vector<Row>& rows) {
  const std::vector<double> errors = driving_servo_errors_rad(rows);
  return errors.empty() ? 0.0 : *std::ranges::max_element(errors);
}

}  // namespace swivel::second
