// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/outside_effects.hpp"

#include <stdexcept>

#include "assignment.hpp"
#include "effect_checks.hpp"

namespace swivel::independent {
namespace {

std::vector<ParamSlot> outside_slots(Robot robot) {
  const auto wheels = static_cast<double>(wheel_count(robot));
  std::vector<ParamSlot> s;
  s.push_back(make_slot(
      "floor_drift", "vx_mps", -0.05, 0.05,
      [](auto& r) -> auto& { return r.outside.floor_drift_x_mps; }));
  s.push_back(make_slot(
      "floor_drift", "vy_mps", -0.05, 0.05,
      [](auto& r) -> auto& { return r.outside.floor_drift_y_mps; }));
  s.push_back(make_slot(
      "dropped_counts", "interval_s", 0.0, 1.0e4,
      [](auto& r) -> auto& { return r.outside.dropped_counts_interval_s; }));
  s.push_back(make_slot(
      "dropped_counts", "min_counts", 1.0, 1.0e4,
      [](auto& r) -> auto& { return r.outside.dropped_counts_min; }));
  s.push_back(make_slot(
      "dropped_counts", "max_counts", 1.0, 1.0e4,
      [](auto& r) -> auto& { return r.outside.dropped_counts_max; }));
  s.push_back(make_slot(
      "eccentric_wheel", "wheel", 0.0, wheels,
      [](auto& r) -> auto& { return r.outside.eccentric_wheel; }));
  s.push_back(make_slot(
      "eccentric_wheel", "amplitude", 0.0, 0.2,
      [](auto& r) -> auto& { return r.outside.eccentric_amplitude; }));
  s.push_back(make_slot(
      "gyro_drift", "rad_s", -0.5, 0.5,
      [](auto& r) -> auto& { return r.outside.gyro_drift_rad_s; }));
  return s;
}

}  // namespace

void set_outside_effect(RunSpec& spec, const std::string& assignment) {
  const Assignment a = parse_assignment(assignment);
  apply_assignment(spec, a, outside_slots(spec.robot), {}, robot_name(spec.robot) + " robot");
}

std::vector<std::string> outside_effect_keys() {
  std::vector<std::string> keys;
  for (const ParamSlot& s : outside_slots(Robot::kSwpc4)) keys.push_back(s.effect + "." + s.param);
  return keys;
}

std::vector<std::string> active_outside_effects(const OutsideEffects& o) {
  std::vector<std::string> names;
  if (o.floor_drift_x_mps != 0.0 || o.floor_drift_y_mps != 0.0) names.emplace_back("floor_drift");
  if (o.dropped_counts_interval_s > 0.0) names.emplace_back("dropped_counts");
  if (o.eccentric_wheel > 0 && o.eccentric_amplitude > 0.0) {
    names.emplace_back("eccentric_wheel");
  }
  if (o.gyro_drift_rad_s != 0.0) names.emplace_back("gyro_drift");
  return names;
}

void check_outside_effects(const RunSpec& spec) {
  for (const ParamSlot& s : outside_slots(spec.robot)) {
    const double v = s.get(spec);
    if (!(v >= s.min && v <= s.max)) {
      throw std::invalid_argument("outside: " + s.effect + "." + s.param + "=" + format_number(v) +
                                  ": outside [" + format_number(s.min) + ", " +
                                  format_number(s.max) + "]");
    }
  }
  const OutsideEffects& o = spec.outside;
  if (o.dropped_counts_min > o.dropped_counts_max) {
    throw std::invalid_argument(
        "outside: dropped_counts.min_counts=" + std::to_string(o.dropped_counts_min) +
        " exceeds max_counts=" + std::to_string(o.dropped_counts_max));
  }
  if (o.dropped_counts_interval_s > 0.0 && o.dropped_counts_interval_s < 0.1) {
    throw std::invalid_argument(
        "outside: dropped_counts.interval_s=" + format_number(o.dropped_counts_interval_s) +
        ": at least 0.1 (or 0 for none)");
  }
}

}  // namespace swivel::independent
