// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/library_effects.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "assignment.hpp"
#include "effect_checks.hpp"
#include "swivel/independent/nominal_robots.hpp"

namespace swivel::independent {
namespace {

constexpr double kMaxScale = 2.0;
constexpr double kMinScale = 0.5;

std::string module_key(std::size_t i, const char* suffix) {
  return "module_" + std::to_string(i + 1) + "_" + suffix;
}

std::vector<ParamSlot> true_slots(Robot robot) {
  std::vector<ParamSlot> s;
  s.push_back(make_slot(
      "gyro_bias", "bias_rad_s", -0.5, 0.5,
      [](auto& r) -> auto& { return r.truth.gyro_bias_rad_s; }));
  s.push_back(make_slot(
      "gyro_scale", "scale", kMinScale, kMaxScale,
      [](auto& r) -> auto& { return r.truth.gyro_scale; }));
  if (robot == Robot::kDocent) {
    s.push_back(make_slot(
        "wheel_radius", "left_scale", kMinScale, kMaxScale,
        [](auto& r) -> auto& { return r.truth.wheel_radius_scale[0]; }));
    s.push_back(make_slot(
        "wheel_radius", "right_scale", kMinScale, kMaxScale,
        [](auto& r) -> auto& { return r.truth.wheel_radius_scale[1]; }));
    s.push_back(make_slot(
        "track_width", "scale", kMinScale, kMaxScale,
        [](auto& r) -> auto& { return r.truth.track_width_scale; }));
  } else {
    for (std::size_t i = 0; i < 4; ++i) {
      s.push_back(make_slot(
          "wheel_radius", module_key(i, "scale"), kMinScale,
          kMaxScale, [i](auto& r) -> auto& { return r.truth.wheel_radius_scale[i]; }));
    }
    for (std::size_t i = 0; i < 4; ++i) {
      s.push_back(make_slot(
          "caster_offset", module_key(i, "scale"), kMinScale,
          kMaxScale, [i](auto& r) -> auto& { return r.truth.caster_offset_scale[i]; }));
    }
    for (std::size_t i = 0; i < 4; ++i) {
      s.push_back(make_slot(
          "steering_offset", module_key(i, "rad"), -0.5,
          0.5, [i](auto& r) -> auto& { return r.truth.steering_offset_rad[i]; }));
    }
  }
  s.push_back(make_slot(
      "sensor_latency", "delay_s", 0.0, 0.5,
      [](auto& r) -> auto& { return r.truth.sensor_delay_s; }));
  s.push_back(make_slot(
      "actuator_lag", "time_constant_s", 0.0, 1.0,
      [](auto& r) -> auto& { return r.truth.actuator_time_constant_s; }));
  if (robot == Robot::kSwpc4) {
    s.push_back(make_slot(
        "steering_lag", "time_constant_s", 0.0, 1.0,
        [](auto& r) -> auto& { return r.truth.steering_time_constant_s; }));
    s.push_back(make_slot(
        "steering_rate_limit", "radps", 0.1, 1000.0,
        [](auto& r) -> auto& { return r.truth.steering_rate_limit_radps; }));
  }
  s.push_back(make_slot(
      "accel_limit", "linear_mps2", 0.01, 1000.0,
      [](auto& r) -> auto& { return r.truth.linear_accel_limit_mps2; }));
  s.push_back(make_slot(
      "accel_limit", "angular_radps2", 0.01, 1000.0,
      [](auto& r) -> auto& { return r.truth.angular_accel_limit_radps2; }));
  s.push_back(make_slot(
      "slip", "gain_per_radps2", 0.0, 0.05,
      [](auto& r) -> auto& { return r.truth.slip_gain_per_radps2; }));
  return s;
}

// Effects of the library that only one of the robots has.
std::vector<std::string> effects_of_other_robot(Robot robot) {
  if (robot == Robot::kDocent) {
    return {"caster_offset", "steering_offset", "steering_lag", "steering_rate_limit"};
  }
  return {"track_width"};
}

ExpectedEffect effect_with(const std::string& name, const std::vector<ParamSlot>& slots,
                           const RunSpec& spec) {
  ExpectedEffect e{name, {}};
  for (const ParamSlot& s : slots) {
    if (s.effect == name) e.params.push_back({s.param, s.get(spec)});
  }
  return e;
}

}  // namespace

void set_true_effect(RunSpec& spec, const std::string& assignment) {
  const Assignment a = parse_assignment(assignment);
  apply_assignment(spec, a, true_slots(spec.robot), effects_of_other_robot(spec.robot),
                   robot_name(spec.robot) + " robot");
}

std::vector<std::string> true_effect_keys(Robot robot) {
  std::vector<std::string> keys;
  for (const ParamSlot& s : true_slots(robot)) keys.push_back(s.effect + "." + s.param);
  return keys;
}

void check_true_effects(const RunSpec& spec) {
  for (const ParamSlot& s : true_slots(spec.robot)) {
    const double v = s.get(spec);
    if (!(v >= s.min && v <= s.max)) {
      throw std::invalid_argument("truth: " + s.effect + "." + s.param + "=" + format_number(v) +
                                  ": outside [" + format_number(s.min) + ", " +
                                  format_number(s.max) + "]");
    }
  }
  const TrueEffects& t = spec.truth;
  const TrueEffects identity;
  if (spec.robot == Robot::kDocent) {
    const auto refuse = [](const char* effect) {
      throw std::invalid_argument(std::string("truth: ") + effect +
                                  ": not an effect of the docent robot");
    };
    if (t.caster_offset_scale != identity.caster_offset_scale) refuse("caster_offset");
    if (t.steering_offset_rad != identity.steering_offset_rad) refuse("steering_offset");
    if (t.steering_time_constant_s != 0.0) refuse("steering_lag");
    if (t.steering_rate_limit_radps != identity.steering_rate_limit_radps) {
      refuse("steering_rate_limit");
    }
    if (t.wheel_radius_scale[2] != 1.0 || t.wheel_radius_scale[3] != 1.0) {
      throw std::invalid_argument("truth: wheel_radius: the docent has two wheels");
    }
  } else {
    if (t.track_width_scale != 1.0) {
      throw std::invalid_argument("truth: track_width: not an effect of the swpc4 robot");
    }
    if (spec.steering == Steering::kSelfAligning &&
        (t.steering_time_constant_s != 0.0 ||
         t.steering_rate_limit_radps != identity.steering_rate_limit_radps)) {
      throw std::invalid_argument(
          "truth: steering_lag and steering_rate_limit need powered steering (the "
          "self-aligning robot's casters are passive)");
    }
  }
}

std::vector<ExpectedEffect> expected_effects(const RunSpec& spec) {
  const RunSpec& s = spec;
  const std::vector<ParamSlot> slots = true_slots(s.robot);
  const TrueEffects& t = s.truth;
  std::vector<ExpectedEffect> out;
  const auto differs = [&](const std::string& name, double identity) {
    return std::ranges::any_of(slots, [&](const ParamSlot& slot) {
      return slot.effect == name && slot.get(s) != identity;
    });
  };
  if (differs("gyro_bias", 0.0)) out.push_back(effect_with("gyro_bias", slots, s));
  if (differs("gyro_scale", 1.0)) out.push_back(effect_with("gyro_scale", slots, s));
  if (differs("wheel_radius", 1.0)) out.push_back(effect_with("wheel_radius", slots, s));
  if (s.robot == Robot::kDocent && differs("track_width", 1.0)) {
    out.push_back(effect_with("track_width", slots, s));
  }
  if (s.robot == Robot::kSwpc4) {
    if (differs("caster_offset", 1.0)) out.push_back(effect_with("caster_offset", slots, s));
    if (differs("steering_offset", 0.0)) out.push_back(effect_with("steering_offset", slots, s));
  }
  if (differs("sensor_latency", 0.0)) out.push_back(effect_with("sensor_latency", slots, s));
  if (differs("actuator_lag", 0.0)) out.push_back(effect_with("actuator_lag", slots, s));
  if (s.robot == Robot::kSwpc4) {
    if (differs("steering_lag", 0.0)) out.push_back(effect_with("steering_lag", slots, s));
    // Passive casters have no steering drive to limit.
    const bool states_steering = s.model_limits != ModelLimits::kNone;
    if (s.steering == Steering::kPowered &&
        (!states_steering || t.steering_rate_limit_radps != kSteeringRateLimitRadps)) {
      out.push_back(effect_with("steering_rate_limit", slots, s));
    }
  }
  const bool states_accel = s.model_limits == ModelLimits::kAll;
  if (!states_accel || t.linear_accel_limit_mps2 != kLinearAccelLimitMps2 ||
      t.angular_accel_limit_radps2 != kAngularAccelLimitRadps2) {
    out.push_back(effect_with("accel_limit", slots, s));
  }
  if (differs("slip", 0.0)) out.push_back(effect_with("slip", slots, s));
  return out;
}

}  // namespace swivel::independent
