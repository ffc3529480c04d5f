// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/fold_effects.hpp"

#include <charconv>
#include <cstddef>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/robot_model_io.hpp"
#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {
namespace {

// Ranges the robot model's reader accepts (core/src/config/robot_model_io.cpp): a folded value
// outside them would give a model file the daemon refuses, so such an effect stays.
constexpr double kMinGyroScale = 0.5;
constexpr double kMaxGyroScale = 2.0;
constexpr double kMaxGyroBiasRadps = 1.0;
constexpr double kMaxSteeringOffsetRad = 3.2;

std::string number(double value) {
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, value);
  return {buffer, r.ptr};
}

double param_or(const EffectParams& params, const std::string& key, double identity) {
  const auto it = params.find(key);
  return it == params.end() ? identity : it->second;
}

std::string module_key(std::size_t i, const char* suffix) {
  return "module_" + std::to_string(i + 1) + "_" + suffix;
}

// Why the daemon cannot use an effect the robot model has no parameter for.
const std::map<std::string, std::string>& kept_reasons() {
  static const std::map<std::string, std::string> reasons = {
      {"slip",
       "the robot model has no slip parameter: the drivetrains' odometry integrates the "
       "encoders as rolling without slip"},
      {"actuator_lag",
       "the robot model has no actuator response: the drivetrains command wheel and steering "
       "rates and nothing in the daemon predicts how the drives follow them"},
      {"steering_lag",
       "the robot model has no actuator response: the swpc drivetrain commands steering rates "
       "and nothing in the daemon predicts how the drives follow them"},
      {"sensor_latency",
       "the robot model has no latency parameter: the localizations integrate each encoder and "
       "gyro reading as of the loop cycle it arrives in"},
      {"track_scrub",
       "the robot model has no turn-dependent track: the differential drivetrain's odometry "
       "uses one track width for every kind of turn"},
  };
  return reasons;
}

// One parameter changed by folding: "<effect>.<key> = v -> <target> a -> b".
struct Change {
  std::string source;
  std::string target;
  double* field = nullptr;
  double folded = 0.0;
  double min = 0.0;
  double max = 0.0;
  bool bounded = false;
};

// The parameters of `out` that effect `name` folds into, and their folded values (from the
// model's values, as `out` has them); false when no parameter of the robot model holds it.
bool collect_changes(const std::string& name, const EffectParams& params, RobotModel& out,
                     std::vector<Change>& changes) {
  const bool swpc = out.drivetrain == DrivetrainKind::kSwpc;
  const auto scale = [&](const std::string& key, const std::string& target, double& field) {
    const double s = param_or(params, key, 1.0);
    std::string what = name;
    what.append(".").append(key).append(" = ").append(number(s));
    changes.push_back({what, target, &field, field * s});
  };
  const auto add = [&](const std::string& key, const std::string& target, double& field,
                       double limit) {
    const double v = param_or(params, key, 0.0);
    std::string what = name;
    what.append(".").append(key).append(" = ").append(number(v));
    changes.push_back({what, target, &field, field + v, -limit, limit, true});
  };
  if (name == "gyro_bias") {
    add("bias_rad_s", "sensors.gyro.bias_rad_s", out.sensors.gyro.bias_rad_s, kMaxGyroBiasRadps);
  } else if (name == "gyro_scale") {
    scale("scale", "sensors.gyro.scale", out.sensors.gyro.scale);
    changes.back().min = kMinGyroScale;
    changes.back().max = kMaxGyroScale;
    changes.back().bounded = true;
  } else if (name == "wheel_radius" && !swpc) {
    scale("left_scale", "differential.wheel_radius_left_m", out.differential.wheel_radius_left_m);
    scale("right_scale", "differential.wheel_radius_right_m",
          out.differential.wheel_radius_right_m);
  } else if (name == "track_width" && !swpc) {
    scale("scale", "differential.track_width_m", out.differential.track_width_m);
  } else if (swpc &&
             (name == "wheel_radius" || name == "caster_offset" || name == "steering_offset")) {
    for (std::size_t i = 0; i < out.modules.size(); ++i) {
      SwpcModuleParams& m = out.modules[i];
      const std::string where = "swpc.modules[" + std::to_string(i) + "].";
      if (name == "wheel_radius") {
        scale(module_key(i, "scale"), where + "wheel_radius_m", m.wheel_radius_m);
      } else if (name == "caster_offset") {
        scale(module_key(i, "scale"), where + "caster_offset_m", m.caster_offset_m);
      } else {
        add(module_key(i, "rad"), where + "steering_offset_rad", m.steering_offset_rad,
            kMaxSteeringOffsetRad);
      }
    }
  } else if (swpc && name == "module_layout") {
    // The positions of every steering axis, scaled about the robot frame's origin.
    for (std::size_t i = 0; i < out.modules.size(); ++i) {
      SwpcModuleParams& m = out.modules[i];
      const std::string where = "swpc.modules[" + std::to_string(i) + "].";
      scale("longitudinal_scale", where + "x_m", m.x_m);
      scale("lateral_scale", where + "y_m", m.y_m);
    }
  } else {
    return false;
  }
  return true;
}

// Writes `changes` of effect `name` into the model, all or nothing: an effect whose folded
// value the model file could not hold stays whole.
void apply_changes(const std::string& name, const EffectParams& params,
                   const std::vector<Change>& changes, FoldResult& result) {
  const Change* outside = nullptr;
  for (const Change& c : changes) {
    if (c.bounded && !(c.folded >= c.min && c.folded <= c.max)) outside = &c;
  }
  if (outside != nullptr) {
    result.kept.push_back(name + ": folded, " + outside->target + " would be " +
                          number(outside->folded) + ", outside the robot model's [" +
                          number(outside->min) + ", " + number(outside->max) + "]");
    result.model.effects[name] = params;
    return;
  }
  for (const Change& c : changes) {
    result.folded.push_back(c.source + " -> " + c.target + " " + number(*c.field) + " -> " +
                            number(c.folded));
    *c.field = c.folded;
  }
}

}  // namespace

bool folds_into_robot_model(const std::string& name, DrivetrainKind kind) {
  RobotModel scratch;
  scratch.drivetrain = kind;
  std::vector<Change> changes;
  return collect_changes(name, {}, scratch, changes);
}

FoldResult fold_effects(const RobotModel& model) {
  sim::validate_effects(model);
  FoldResult result;
  result.model = model;
  result.model.effects.clear();
  for (const auto& [name, params] : model.effects) {
    std::vector<Change> changes;
    if (collect_changes(name, params, result.model, changes)) {
      apply_changes(name, params, changes, result);
      continue;
    }
    const auto reason = kept_reasons().find(name);
    result.kept.push_back(name + ": " +
                          (reason != kept_reasons().end()
                               ? reason->second
                               : std::string("no parameter of the robot model holds it")));
    result.model.effects[name] = params;
  }
  return result;
}

void write_folded_model(const RobotModel& model, const std::string& title,
                        const std::string& path) {
  const FoldResult fold = fold_effects(model);
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "# " << title << "\n";
  if (fold.folded.empty() && fold.kept.empty()) out << "# nothing named: the nominal model\n";
  for (const std::string& line : fold.folded) out << "# folded: " << line << "\n";
  for (const std::string& line : fold.kept) out << "# kept in effects (" << line << ")\n";
  out << robot_model_to_yaml(fold.model);
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace swivel::model_gap
