// SPDX-License-Identifier: Apache-2.0
#include "swivel/robot_model_io.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/types.hpp"

namespace swivel {
namespace {

constexpr double kMax = std::numeric_limits<double>::max();

// Geometry must be strictly positive; ParamReader's ranges are inclusive.
double positive(ParamReader& r, const std::string& key) {
  const double value = r.number(key);
  if (value <= 0.0) {
    r.fail(key, "expected a positive number, got " + r.node()[key].Scalar());
  }
  return value;
}

DifferentialParams read_differential(ParamReader r) {
  DifferentialParams p;
  p.wheel_radius_left_m = positive(r, "wheel_radius_left_m");
  p.wheel_radius_right_m = positive(r, "wheel_radius_right_m");
  p.track_width_m = positive(r, "track_width_m");
  r.finish();
  return p;
}

std::vector<SwpcModuleParams> read_swpc(ParamReader r) {
  const YAML::Node seq = r.sequence("modules");
  r.finish();
  if (seq.size() < 2 || seq.size() > kMaxModules) {
    r.fail("modules", "expected between 2 and " + std::to_string(kMaxModules) + " modules, got " +
                          std::to_string(seq.size()));
  }
  std::vector<SwpcModuleParams> modules;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    ParamReader m = r.element(seq, "modules", i);
    SwpcModuleParams p;
    p.x_m = m.number("x_m");
    p.y_m = m.number("y_m");
    p.steering_offset_rad = m.number_or("steering_offset_rad", 0.0, -3.2, 3.2);
    p.caster_offset_m = positive(m, "caster_offset_m");
    p.wheel_radius_m = positive(m, "wheel_radius_m");
    m.finish();
    modules.push_back(p);
  }
  return modules;
}

SensorParams read_sensors(ParamReader r) {
  SensorParams s;
  // Real-valued: a geared motor's counts per wheel revolution are not an integer.
  const auto counts = [&r](const std::string& key, double fallback) {
    if (!r.has(key)) return r.number_or(key, fallback);  // marks the key as known
    return positive(r, key);
  };
  s.wheel_encoder_counts_per_rev =
      counts("wheel_encoder_counts_per_rev", s.wheel_encoder_counts_per_rev);
  s.steering_encoder_counts_per_rev =
      counts("steering_encoder_counts_per_rev", s.steering_encoder_counts_per_rev);
  ParamReader gyro = r.child("gyro");
  s.gyro.scale = gyro.number_or("scale", s.gyro.scale, 0.5, 2.0);
  s.gyro.bias_rad_s = gyro.number_or("bias_rad_s", s.gyro.bias_rad_s, -1.0, 1.0);
  s.gyro.noise_rad_s = gyro.number_or("noise_rad_s", s.gyro.noise_rad_s, 0.0, 1.0);
  gyro.finish();
  ParamReader mocap = r.child("motion_capture");
  auto& mc = s.motion_capture;
  mc.position_noise_m = mocap.number_or("position_noise_m", mc.position_noise_m, 0.0, 1.0);
  mc.yaw_noise_rad = mocap.number_or("yaw_noise_rad", mc.yaw_noise_rad, 0.0, 1.0);
  mc.rate_hz = mocap.number_or("rate_hz", mc.rate_hz, 0.1, 10000.0);
  mocap.finish();
  r.finish();
  return s;
}

// Every limit is optional and strictly positive; the section itself may be absent.
MotionLimits read_limits(ParamReader r, DrivetrainKind drivetrain) {
  MotionLimits l;
  const auto limit = [&r](const char* key, std::optional<double>& out) {
    const double value = r.number_or(key, 0.0);  // marks the key as known
    if (!r.has(key)) return;
    if (!(value > 0.0)) r.fail(key, "expected a positive number, got " + r.node()[key].Scalar());
    out = value;
  };
  limit("linear_velocity_mps", l.linear_velocity_mps);
  limit("angular_velocity_radps", l.angular_velocity_radps);
  limit("linear_acceleration_mps2", l.linear_acceleration_mps2);
  limit("angular_acceleration_radps2", l.angular_acceleration_radps2);
  limit("linear_jerk_mps3", l.linear_jerk_mps3);
  limit("angular_jerk_radps3", l.angular_jerk_radps3);
  if (drivetrain == DrivetrainKind::kSwpc) {
    limit("steering_rate_radps", l.steering_rate_radps);
  } else if (r.has("steering_rate_radps")) {
    r.fail("steering_rate_radps", "applies to swpc robots only (this one is differential)");
  }
  r.finish();
  return l;
}

// The characters a name may hold and still be written as a plain YAML scalar.
bool is_name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-' || c == '.';
}

// Effect and parameter names are identifiers, as the simulator and the model-gap workflow
// name them. Holding them to that also keeps every name inside YAML's 1024-character limit
// on a key once it is written back, so a model that parses always reads back.
constexpr std::size_t kMaxEffectNameLength = 64;

bool is_effect_name(const YAML::Node& key) {
  if (!key.IsScalar()) return false;
  const std::string& name = key.Scalar();
  if (name.empty() || name.size() > kMaxEffectNameLength) return false;
  return std::ranges::all_of(name, is_name_char);
}

// What a name must be, for the error message: `what` is "effect" or "effect parameter".
std::string effect_name_rule(const char* what) {
  return std::string(what) + " names must be 1 to " + std::to_string(kMaxEffectNameLength) +
         " letters, digits, '_', '-' or '.' (like gyro_bias or bias_rad_s)";
}

std::map<std::string, EffectParams> read_effects(ParamReader r) {
  std::map<std::string, EffectParams> effects;
  const YAML::Node& node = r.node();
  if (!node.IsMap()) return effects;
  for (auto it = node.begin(); it != node.end(); ++it) {
    if (!is_effect_name(it->first)) r.fail("", effect_name_rule("effect"));
    const std::string name = it->first.Scalar();
    ParamReader effect = r.child(name);
    EffectParams params;
    if (effect.node().IsMap()) {
      for (auto p = effect.node().begin(); p != effect.node().end(); ++p) {
        if (!is_effect_name(p->first)) {
          effect.fail("", effect_name_rule("effect parameter"));
        }
        const std::string key = p->first.Scalar();
        params[key] = effect.number(key, -kMax, kMax);
      }
    }
    effect.finish();
    effects[name] = params;
  }
  r.finish();
  return effects;
}

YAML::Node parse_yaml(const std::string& text, const std::string& source_name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    std::string where = source_name;
    if (!e.mark.is_null()) {
      where += ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1);
    }
    throw ConfigError(where + ": invalid YAML: " + e.msg);
  }
}

// Shortest text that reads back as the same double.
std::string num(double value) {
  char buf[64];
  const auto result = std::to_chars(buf, buf + sizeof buf, value);
  return {buf, result.ptr};
}

// YAML 1.1/1.2 words that a plain scalar would turn into a bool or null.
bool is_yaml_keyword(const std::string& value) {
  std::string lower;
  for (const char c : value)
    lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static constexpr std::array<std::string_view, 10> kKeywords = {
      "true", "false", "null", "yes", "no", "on", "off", "y", "n", "~"};
  return std::ranges::find(kKeywords, lower) != kKeywords.end();
}

// Plain scalar when it is safe, else a double-quoted one with every control byte escaped,
// so that any string reads back unchanged.
std::string text(const std::string& value) {
  bool plain = !value.empty() && !is_yaml_keyword(value);
  plain = plain && std::ranges::all_of(value, is_name_char);
  if (plain && !(value[0] >= '0' && value[0] <= '9') && value[0] != '-' && value[0] != '.') {
    return value;
  }
  std::string out = "\"";
  for (const char c : value) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20 || byte == 0x7f) {
      char escaped[8];
      (void)std::snprintf(escaped, sizeof escaped, "\\x%02x", byte);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

RobotModel parse_robot_model(const std::string& yaml_text, const std::string& source_name) {
  const YAML::Node root = parse_yaml(yaml_text, source_name);
  ParamReader r(root, source_name, "");
  RobotModel model;
  model.source_file = source_name;
  model.name = r.string("name");
  r.string("drivetrain");  // reports a missing key before the choice is checked
  const std::string kind = r.choice_or("drivetrain", "", {"differential", "swpc"});
  model.drivetrain = kind == "swpc" ? DrivetrainKind::kSwpc : DrivetrainKind::kDifferential;
  const std::string other = kind == "swpc" ? "differential" : "swpc";
  if (r.has(other)) {
    r.fail(other,
           "section does not match drivetrain '" + kind + "' (expected a '" + kind + "' section)");
  }
  if (!r.has(kind)) {
    r.fail("", "missing required key '" + kind + "' (drivetrain is " + kind + ")");
  }
  if (model.drivetrain == DrivetrainKind::kDifferential) {
    model.differential = read_differential(r.child("differential"));
  } else {
    model.modules = read_swpc(r.child("swpc"));
  }
  model.sensors = read_sensors(r.child("sensors"));
  model.limits = read_limits(r.child("limits"), model.drivetrain);
  model.effects = read_effects(r.child("effects"));
  r.finish();
  return model;
}

RobotModel load_robot_model(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot read robot model file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_robot_model(text.str(), path);
}

std::string robot_model_to_yaml(const RobotModel& model) {
  std::ostringstream out;
  const bool swpc = model.drivetrain == DrivetrainKind::kSwpc;
  out << "name: " << text(model.name) << "\n";
  out << "drivetrain: " << (swpc ? "swpc" : "differential") << "\n";
  if (swpc) {
    out << "swpc:\n  modules:\n";
    for (const auto& m : model.modules) {
      out << "    - {x_m: " << num(m.x_m) << ", y_m: " << num(m.y_m)
          << ", steering_offset_rad: " << num(m.steering_offset_rad)
          << ", caster_offset_m: " << num(m.caster_offset_m)
          << ", wheel_radius_m: " << num(m.wheel_radius_m) << "}\n";
    }
  } else {
    const auto& d = model.differential;
    out << "differential:\n"
        << "  wheel_radius_left_m: " << num(d.wheel_radius_left_m) << "\n"
        << "  wheel_radius_right_m: " << num(d.wheel_radius_right_m) << "\n"
        << "  track_width_m: " << num(d.track_width_m) << "\n";
  }
  const auto& s = model.sensors;
  out << "sensors:\n"
      << "  wheel_encoder_counts_per_rev: " << num(s.wheel_encoder_counts_per_rev) << "\n"
      << "  steering_encoder_counts_per_rev: " << num(s.steering_encoder_counts_per_rev) << "\n";
  out << "  gyro: {scale: " << num(s.gyro.scale) << ", bias_rad_s: " << num(s.gyro.bias_rad_s)
      << ", noise_rad_s: " << num(s.gyro.noise_rad_s) << "}\n"
      << "  motion_capture: {position_noise_m: " << num(s.motion_capture.position_noise_m)
      << ", yaw_noise_rad: " << num(s.motion_capture.yaw_noise_rad)
      << ", rate_hz: " << num(s.motion_capture.rate_hz) << "}\n";
  const MotionLimits& l = model.limits;
  if (l.any()) {
    out << "limits:\n";
    const auto limit = [&out](const char* key, const std::optional<double>& value) {
      if (value) out << "  " << key << ": " << num(*value) << "\n";
    };
    limit("linear_velocity_mps", l.linear_velocity_mps);
    limit("angular_velocity_radps", l.angular_velocity_radps);
    limit("linear_acceleration_mps2", l.linear_acceleration_mps2);
    limit("angular_acceleration_radps2", l.angular_acceleration_radps2);
    limit("linear_jerk_mps3", l.linear_jerk_mps3);
    limit("angular_jerk_radps3", l.angular_jerk_radps3);
    limit("steering_rate_radps", l.steering_rate_radps);
  }
  if (model.effects.empty()) {
    out << "effects: {}\n";
  } else {
    out << "effects:\n";
    for (const auto& [name, params] : model.effects) {
      out << "  " << text(name) << ": {";
      bool first = true;
      for (const auto& [key, value] : params) {
        out << (first ? "" : ", ") << text(key) << ": " << num(value);
        first = false;
      }
      out << "}\n";
    }
  }
  return out.str();
}

void save_robot_model(const RobotModel& model, const std::string& path) {
  std::ofstream out(path, std::ios::trunc);
  if (!out) {
    throw std::runtime_error(path + ": cannot open robot model file for writing (" +
                             std::strerror(errno) + ")");
  }
  out << robot_model_to_yaml(model);
  out.close();
  if (!out) throw std::runtime_error(path + ": cannot write robot model file");
}

}  // namespace swivel
