// SPDX-License-Identifier: Apache-2.0
// How much of a run's drivetrain geometry its body motion carries (README.md, "What a
// run can show").
#include <algorithm>
#include <cmath>
#include <vector>

#include "open_loop.hpp"
#include "swivel/second/second_robot.hpp"

namespace swivel::second {
namespace {

// Whether the truth's drivetrain geometry differs from the nominal robot's.
bool has_geometry(const Truth& t) {
  const auto off = [](const std::vector<double>& v, double neutral) {
    return std::ranges::any_of(v, [neutral](double x) { return x != neutral; });
  };
  return off(t.wheel_radius_scale, 1.0) || off(t.caster_offset_scale, 1.0) ||
         off(t.steering_offset_rad, 0.0) || t.track_width_scale != 1.0;
}

// The truth with every geometry deviation multiplied by `share` (0: the nominal geometry).
Truth scaled_geometry(Truth t, double share) {
  const auto scale = [share](std::vector<double>& v, double neutral) {
    for (double& x : v) x = neutral + share * (x - neutral);
  };
  scale(t.wheel_radius_scale, 1.0);
  scale(t.caster_offset_scale, 1.0);
  scale(t.steering_offset_rad, 0.0);
  t.track_width_scale = 1.0 + share * (t.track_width_scale - 1.0);
  return t;
}

}  // namespace

double motion_apart_per_metre(const std::vector<Row>& a, const std::vector<Row>& b,
                              double row_rate_hz) {
  const auto step = static_cast<std::size_t>(std::max(1.0, std::round(row_rate_hz)));
  const auto in_body = [](const Row& from, const Row& to, double& x, double& y) {
    const double dx = to.pose[0] - from.pose[0];
    const double dy = to.pose[1] - from.pose[1];
    const double c = std::cos(from.pose[2]);
    const double s = std::sin(from.pose[2]);
    x = c * dx + s * dy;
    y = -s * dx + c * dy;
  };
  double apart = 0;
  double path = 0;
  for (std::size_t j = step; j < std::min(a.size(), b.size()); j += step) {
    double ax = 0;
    double ay = 0;
    double bx = 0;
    double by = 0;
    in_body(a[j - step], a[j], ax, ay);
    in_body(b[j - step], b[j], bx, by);
    apart += std::hypot(bx - ax, by - ay);
    path += std::hypot(ax, ay);
  }
  return path > 0 ? apart / path : 0.0;
}

std::optional<GeometryFootprint> geometry_footprint(const RunSpec& spec) {
  if (!has_geometry(spec.truth)) return std::nullopt;
  RunSpec quiet = spec;
  quiet.noise = false;
  quiet.truth = scaled_geometry(spec.truth, 0.0);
  // The nominal robot's commands for all three: the path controller would steer the others
  // back onto the path and hide what their geometry does.
  std::vector<double> commands;
  const std::vector<Row> nominal = simulate_commanded(quiet, nullptr, &commands);
  const auto apart_at = [&](double share) {
    quiet.truth = scaled_geometry(spec.truth, share);
    return motion_apart_per_metre(nominal, simulate_commanded(quiet, &commands, nullptr),
                                  spec.row_rate_hz);
  };
  GeometryFootprint f;
  f.full = apart_at(1.0);
  f.half = apart_at(0.5);
  return f;
}

}  // namespace swivel::second
