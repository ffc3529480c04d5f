// SPDX-License-Identifier: Apache-2.0
#include "swivel/sim/effects.hpp"

#include <charconv>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace swivel::sim {
namespace {

constexpr double kMaxSlipGain = 1.0;
constexpr double kMaxLagS = 5.0;
constexpr double kMaxDelayS = 1.0;

std::string module_key(std::size_t i, const char* suffix) {
  return "module_" + std::to_string(i + 1) + "_" + suffix;
}

std::string format_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// A parameter of an effect the model may not carry (nullptr).
double param_or(const EffectParams* params, const std::string& key, double identity) {
  if (params == nullptr) return identity;
  const auto it = params->find(key);
  return it == params->end() ? identity : it->second;
}

std::string names_of(const std::vector<EffectInfo>& library) {
  std::string out;
  for (const EffectInfo& e : library) out += (out.empty() ? "" : ", ") + e.name;
  return out;
}

std::string keys_of(const EffectInfo& effect) {
  std::string out;
  for (const EffectParamInfo& p : effect.params) out += (out.empty() ? "" : ", ") + p.key;
  return out;
}

const char* drivetrain_name(DrivetrainKind kind) {
  return kind == DrivetrainKind::kSwpc ? "swpc" : "differential";
}

}  // namespace

std::vector<EffectInfo> effect_library(const RobotModel& model) {
  const bool swpc = model.drivetrain == DrivetrainKind::kSwpc;
  const std::size_t n = swpc ? model.modules.size() : 2;
  std::vector<EffectInfo> lib;
  lib.push_back({"gyro_bias",
                 "constant gyro bias added to the model's",
                 {{"bias_rad_s", 0.0, -1.0, 1.0, "added bias, rad/s"}}});
  lib.push_back({"gyro_scale",
                 "gyro scale factor multiplying the model's",
                 {{"scale", 1.0, 0.5, 2.0, "factor on the gyro scale"}}});
  EffectInfo radius{"wheel_radius", "true wheel radius = model radius * scale", {}};
  if (swpc) {
    for (std::size_t i = 0; i < n; ++i) {
      radius.params.push_back(
          {module_key(i, "scale"), 1.0, 0.5, 1.5, "factor on module " + std::to_string(i + 1)});
    }
  } else {
    radius.params.push_back({"left_scale", 1.0, 0.5, 1.5, "factor on the left wheel radius"});
    radius.params.push_back({"right_scale", 1.0, 0.5, 1.5, "factor on the right wheel radius"});
  }
  lib.push_back(radius);
  if (!swpc) {
    lib.push_back({"track_width",
                   "true track width = model track width * scale",
                   {{"scale", 1.0, 0.5, 1.5, "factor on the track width"}}});
    lib.push_back(
        {"track_scrub",
         "the effective track depends on how the robot turns (tyre scrub): track * (1 + "
         "(spin_scale - 1) s), s = |w_r - w_l| / (|w_r + w_l| + |w_r - w_l|) of the wheel "
         "rates (1 on the spot, 0 straight)",
         {{"spin_scale", 1.0, 0.8, 1.2,
           "effective track turning on the spot over that on straight and gently "
           "curved paths"}}});
  } else {
    EffectInfo caster{"caster_offset", "true caster offset = model caster offset * scale", {}};
    EffectInfo steer{"steering_offset",
                     "true steering offset = model offset + rad (encoder reads true - offset)",
                     {}};
    for (std::size_t i = 0; i < n; ++i) {
      caster.params.push_back(
          {module_key(i, "scale"), 1.0, 0.1, 5.0, "factor on module " + std::to_string(i + 1)});
      steer.params.push_back({module_key(i, "rad"), 0.0, -std::numbers::pi, std::numbers::pi,
                              "added offset of module " + std::to_string(i + 1) + ", rad"});
    }
    lib.push_back(caster);
    lib.push_back(steer);
    lib.push_back({"module_layout",
                   "true module positions: each steering axis's y = model y * lateral_scale, x = "
                   "model x * longitudinal_scale (about the robot frame's origin)",
                   {{"lateral_scale", 1.0, 0.5, 1.5, "factor on every module's y"},
                    {"longitudinal_scale", 1.0, 0.5, 1.5, "factor on every module's x"}}});
  }

  lib.push_back({"slip",
                 "longitudinal slip growing with wheel acceleration: the contact rolls "
                 "r (psi_dot - gain |psi_dot| psi_ddot)",
                 {{"gain_per_radps2", 0.0, -kMaxSlipGain, kMaxSlipGain,
                   "slip ratio per rad/s^2 of wheel acceleration"}}});
  lib.push_back({"actuator_lag",
                 "wheel and steering rates follow their setpoints through a first-order lag",
                 {{"time_constant_s", 0.0, 0.0, kMaxLagS, "time constant, s"}}});
  if (swpc) {
    lib.push_back({"steering_lag",
                   "the steering drives' rates follow their setpoints through a first-order lag",
                   {{"time_constant_s", 0.0, 0.0, kMaxLagS, "time constant, s"}}});
  }
  lib.push_back({"sensor_latency",
                 "encoders and gyro report the state of delay_s ago (motion capture does not)",
                 {{"delay_s", 0.0, 0.0, kMaxDelayS, "delay, s"}}});
  return lib;
}

const EffectInfo* find_effect(const std::vector<EffectInfo>& library, const std::string& name) {
  for (const EffectInfo& e : library) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

void validate_effects(const RobotModel& model) {
  const std::vector<EffectInfo> lib = effect_library(model);
  for (const auto& [name, params] : model.effects) {
    const EffectInfo* effect = find_effect(lib, name);
    if (effect == nullptr) {
      // Name the drivetrain when the effect exists for the other one.
      RobotModel other = model;
      other.drivetrain = model.drivetrain == DrivetrainKind::kSwpc ? DrivetrainKind::kDifferential
                                                                   : DrivetrainKind::kSwpc;
      const bool elsewhere = find_effect(effect_library(other), name) != nullptr;
      throw std::invalid_argument("effects." + name + ": " +
                                  (elsewhere ? std::string("not available for a ") +
                                                   drivetrain_name(model.drivetrain) + " robot"
                                             : std::string("unknown effect")) +
                                  " (available: " + names_of(lib) + ")");
    }
    for (const auto& [key, value] : params) {
      const EffectParamInfo* info = nullptr;
      for (const EffectParamInfo& p : effect->params) {
        if (p.key == key) info = &p;
      }
      std::string message = "effects.";
      message.append(name).append(".").append(key).append(": ");
      if (info == nullptr) {
        message.append("unknown parameter (expected: ").append(keys_of(*effect)).append(")");
        throw std::invalid_argument(message);
      }
      if (!std::isfinite(value) || value < info->min || value > info->max) {
        message.append(format_number(value))
            .append(" is outside [")
            .append(format_number(info->min))
            .append(", ")
            .append(format_number(info->max))
            .append("]");
        throw std::invalid_argument(message);
      }
    }
  }
}

void set_effect(RobotModel& model, const std::string& assignment) {
  const std::size_t dot = assignment.find('.');
  const std::size_t eq = assignment.find('=');
  if (dot == std::string::npos || eq == std::string::npos || dot == 0 || eq < dot + 2 ||
      eq + 1 >= assignment.size()) {
    throw std::invalid_argument("effect '" + assignment + "': expected NAME.PARAM=VALUE");
  }
  const std::string name = assignment.substr(0, dot);
  const std::string key = assignment.substr(dot + 1, eq - dot - 1);
  const std::string text = assignment.substr(eq + 1);
  double value = 0.0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size()) {
    throw std::invalid_argument("effect '" + assignment + "': '" + text + "' is not a number");
  }
  RobotModel candidate = model;
  candidate.effects[name][key] = value;
  validate_effects(candidate);
  model.effects = std::move(candidate.effects);
}

double spin_share(double left, double right) {
  const double turn = std::abs(right - left);
  const double total = std::abs(right + left) + turn;
  return total > 0.0 ? turn / total : 0.0;
}

DifferentialParams effective_differential(const PlantParams& plant, double left, double right) {
  DifferentialParams d = plant.differential;
  if (plant.track_spin_scale != 1.0) {
    d.track_width_m *= 1.0 + (plant.track_spin_scale - 1.0) * spin_share(left, right);
  }
  return d;
}

PlantParams resolve_plant(const RobotModel& model) {
  validate_effects(model);
  PlantParams p;
  p.drivetrain = model.drivetrain;
  p.sensors = model.sensors;
  const auto effect = [&model](const char* name) -> const EffectParams* {
    const auto it = model.effects.find(name);
    return it == model.effects.end() ? nullptr : &it->second;
  };
  const EffectParams* radius = effect("wheel_radius");
  p.sensors.gyro.bias_rad_s += param_or(effect("gyro_bias"), "bias_rad_s", 0.0);
  p.sensors.gyro.scale *= param_or(effect("gyro_scale"), "scale", 1.0);

  if (model.drivetrain == DrivetrainKind::kDifferential) {
    p.module_count = 2;
    p.differential = model.differential;
    p.differential.wheel_radius_left_m *= param_or(radius, "left_scale", 1.0);
    p.differential.wheel_radius_right_m *= param_or(radius, "right_scale", 1.0);
    p.differential.track_width_m *= param_or(effect("track_width"), "scale", 1.0);
    p.track_spin_scale = param_or(effect("track_scrub"), "spin_scale", 1.0);
  } else {
    if (model.modules.size() < 2 || model.modules.size() > kMaxModules) {
      throw std::invalid_argument("swpc model '" + model.name + "' has " +
                                  std::to_string(model.modules.size()) + " modules; expected 2.." +
                                  std::to_string(kMaxModules));
    }
    const EffectParams* caster = effect("caster_offset");
    const EffectParams* steer = effect("steering_offset");
    const EffectParams* layout = effect("module_layout");
    const double lateral = param_or(layout, "lateral_scale", 1.0);
    const double longitudinal = param_or(layout, "longitudinal_scale", 1.0);
    p.module_count = model.modules.size();
    for (std::size_t i = 0; i < p.module_count; ++i) {
      SwpcModuleParams m = model.modules[i];
      m.wheel_radius_m *= param_or(radius, module_key(i, "scale"), 1.0);
      m.caster_offset_m *= param_or(caster, module_key(i, "scale"), 1.0);
      m.steering_offset_rad += param_or(steer, module_key(i, "rad"), 0.0);
      m.x_m *= longitudinal;
      m.y_m *= lateral;
      p.modules[i] = m;
    }
  }
  p.slip_gain_per_radps2 = param_or(effect("slip"), "gain_per_radps2", 0.0);
  p.actuator_time_constant_s = param_or(effect("actuator_lag"), "time_constant_s", 0.0);
  const EffectParams* steering_lag = effect("steering_lag");
  p.steering_time_constant_s = steering_lag == nullptr
                                   ? p.actuator_time_constant_s
                                   : param_or(steering_lag, "time_constant_s", 0.0);
  p.limits = model.limits;
  p.sensor_delay_s = param_or(effect("sensor_latency"), "delay_s", 0.0);
  return p;
}

}  // namespace swivel::sim
