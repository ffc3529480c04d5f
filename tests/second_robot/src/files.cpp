// SPDX-License-Identifier: Apache-2.0
// The run log and the nominal model as text, the expected answer, and truth assignments.

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/second/second_robot.hpp"

namespace swivel::second {
namespace {

std::string number(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return {buf, res.ptr};
}

std::string yaml_number(double v) {
  std::string s = number(v);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

double stated_counts(double counts, const ModelStatement& m) {
  return m.fractional_counts ? counts * kFractionalGear : counts;
}

std::string counts_text(double counts) {
  return counts == std::floor(counts) ? number(counts) : yaml_number(counts);
}

}  // namespace

std::vector<ExpectedEffect> expected_effects(const RunSpec& spec) {
  const Design d = design(spec.design);
  const Truth& t = spec.truth;
  const bool swpc = d.drive == Drive::kSwpc;
  const std::size_t n = d.wheel_count();
  std::vector<ExpectedEffect> out;
  const auto per_wheel = [&](const std::string& effect, const std::vector<double>& v,
                             double identity, const std::string& suffix) {
    bool differs = false;
    ExpectedEffect e{effect, {}};
    for (std::size_t i = 0; i < n; ++i) {
      const double value = i < v.size() ? v[i] : identity;
      differs = differs || value != identity;
      std::string key = swpc ? "module_" + std::to_string(i + 1) + suffix
                             : std::string(i == 0 ? "left" : "right") + suffix;
      e.params.emplace_back(key, value);
    }
    if (differs) out.push_back(e);
  };
  if (t.gyro_bias_rad_s != 0.0) out.push_back({"gyro_bias", {{"bias_rad_s", t.gyro_bias_rad_s}}});
  if (t.gyro_scale != 1.0) out.push_back({"gyro_scale", {{"scale", t.gyro_scale}}});
  per_wheel("wheel_radius", t.wheel_radius_scale, 1.0, "_scale");
  if (!swpc && t.track_width_scale != 1.0) {
    out.push_back({"track_width", {{"scale", t.track_width_scale}}});
  }
  if (swpc) {
    per_wheel("caster_offset", t.caster_offset_scale, 1.0, "_scale");
    per_wheel("steering_offset", t.steering_offset_rad, 0.0, "_rad");
  }
  if (t.sensor_delay_s != 0.0) out.push_back({"sensor_latency", {{"delay_s", t.sensor_delay_s}}});
  if (t.actuator_lag_s != 0.0) {
    out.push_back({"actuator_lag", {{"time_constant_s", t.actuator_lag_s}}});
  }
  if (swpc && t.steering_lag_s != 0.0) {
    out.push_back({"steering_lag", {{"time_constant_s", t.steering_lag_s}}});
  }
  const double lin =
      t.linear_accel_limit_mps2 > 0 ? t.linear_accel_limit_mps2 : d.linear_accel_limit_mps2;
  const double ang = t.angular_accel_limit_radps2 > 0 ? t.angular_accel_limit_radps2
                                                      : d.angular_accel_limit_radps2;
  if (!spec.model.accel_limits || lin != d.linear_accel_limit_mps2 ||
      ang != d.angular_accel_limit_radps2) {
    out.push_back({"accel_limit", {{"linear_mps2", lin}, {"angular_radps2", ang}}});
  }
  if (swpc) {
    const double steer =
        t.steering_rate_limit_radps > 0 ? t.steering_rate_limit_radps : d.steering_rate_limit_radps;
    if (!spec.model.steering_rate_limit || steer != d.steering_rate_limit_radps) {
      out.push_back({"steering_rate_limit", {{"radps", steer}}});
    }
  }
  return out;
}

namespace {

// CSV columns `name`1 .. `name`n, each after a comma.
void append_numbered(std::string& out, const std::string& name, std::size_t n) {
  for (std::size_t i = 1; i <= n; ++i) out += "," + name + std::to_string(i);
}

// Each value after a comma.
template <typename Values>
void append_values(std::string& out, const Values& values) {
  for (double v : values) out += "," + number(v);
}

std::string run_log_text(const RunSpec& spec, const std::vector<Row>& rows) {
  const Design d = design(spec.design);
  const bool swpc = d.drive == Drive::kSwpc;
  const std::size_t n = d.wheel_count();
  std::string out = "# swivel-run 1\n# robot: " + d.name + "\n";
  out += swpc ? "# drivetrain: swpc\n# modules: " + std::to_string(n) + "\n"
              : "# drivetrain: differential\n";
  out += "# source: swivel-second-run (second robot generator), seed " + std::to_string(spec.seed) +
         ", " + number(spec.row_rate_hz) + " Hz rows, script " + script_name(spec.script) + "\n";
  // Motion capture without latency or clock drift is as good as stamped on the robot's clock;
  // with its own latency it is not, and the workflow fits the offset; a clock that also runs
  // at its own rate leaves the header silent, and the workflow fits the rate too.
  if (spec.truth.mocap_clock_rate == 0.0) {
    out += spec.truth.mocap_latency_s == 0.0 ? "# truth_clock: shared\n"
                                             : "# truth_clock: same_rate\n";
  }
  out += "t,cmd_vx,cmd_vy,cmd_wz";
  if (swpc) {
    append_numbered(out, "steer_", n);
    append_numbered(out, "wheel_", n);
  } else {
    out += ",wheel_l,wheel_r";
  }
  out += ",gyro_wz,truth_x,truth_y,truth_yaw\n";
  for (const Row& r : rows) {
    out += number(r.t_s);
    append_values(out, r.cmd);
    append_values(out, r.steer_rad);
    append_values(out, r.wheel_rad);
    out += "," + number(r.gyro_radps);
    if (r.has_mocap) {
      append_values(out, r.mocap);
    } else {
      out += ",,,";
    }
    out += "\n";
  }
  return out;
}

std::string hidden_state_text(const RunSpec& spec, const std::vector<Row>& rows) {
  const Design d = design(spec.design);
  const bool swpc = d.drive == Drive::kSwpc;
  const std::size_t n = d.wheel_count();
  std::string out = "# swivel-second-run hidden state, seed " + std::to_string(spec.seed) +
                    ": the generator's truth at each row of the run log\n";
  out += "# body twist in the body frame; servo error: reference minus true steering angle\n";
  out += "t,x,y,yaw,vx,vy,wz";
  append_numbered(out, "true_wheel_", n);
  append_numbered(out, "contact_speed_", n);
  if (swpc) {
    append_numbered(out, "true_steer_", n);
    append_numbered(out, "servo_error_", n);
  }
  out += "\n";
  for (const Row& r : rows) {
    out += number(r.t_s);
    append_values(out, r.pose);
    append_values(out, r.twist);
    append_values(out, r.true_wheel_rad);
    append_values(out, r.contact_speed_mps);
    append_values(out, r.true_steer_rad);
    append_values(out, r.steering_servo_error_rad);
    out += "\n";
  }
  return out;
}

std::string model_text(const RunSpec& spec) {
  const Design d = design(spec.design);
  const bool swpc = d.drive == Drive::kSwpc;
  std::string y = "# " + d.name + ": nominal model (swivel-second-run)\n";
  y += "name: " + d.name + "\n";
  y += std::string("drivetrain: ") + (swpc ? "swpc" : "differential") + "\n";
  if (swpc) {
    y += "swpc:\n  modules:\n";
    for (const CasterModule& m : d.modules) {
      y += "    - {x_m: " + yaml_number(m.x_m) + ", y_m: " + yaml_number(m.y_m) +
           ", steering_offset_rad: 0.0, caster_offset_m: " + yaml_number(m.caster_offset_m) +
           ", wheel_radius_m: " + yaml_number(m.wheel_radius_m) + "}\n";
    }
  } else {
    y += "differential:\n  wheel_radius_left_m: " + yaml_number(d.wheel_radius_left_m) +
         "\n  wheel_radius_right_m: " + yaml_number(d.wheel_radius_right_m) +
         "\n  track_width_m: " + yaml_number(d.track_width_m) + "\n";
  }
  y += "sensors:\n  wheel_encoder_counts_per_rev: " +
       counts_text(stated_counts(d.wheel_counts_per_rev, spec.model)) + "\n";
  if (swpc) {
    y += "  steering_encoder_counts_per_rev: " +
         counts_text(stated_counts(d.steering_counts_per_rev, spec.model)) + "\n";
  }
  y += "  gyro: {scale: 1.0, bias_rad_s: 0.0, noise_rad_s: " + yaml_number(d.gyro_noise_rad_s) +
       "}\n";
  y += "  motion_capture: {position_noise_m: " + yaml_number(d.mocap_position_noise_m) +
       ", yaw_noise_rad: " + yaml_number(d.mocap_yaw_noise_rad) +
       ", rate_hz: " + yaml_number(d.mocap_rate_hz) + "}\n";
  const bool steer = swpc && spec.model.steering_rate_limit;
  if (spec.model.accel_limits || steer) {
    y += "limits:\n";
    if (spec.model.accel_limits) {
      y += "  linear_acceleration_mps2: " + yaml_number(d.linear_accel_limit_mps2) + "\n";
      y += "  angular_acceleration_radps2: " + yaml_number(d.angular_accel_limit_radps2) + "\n";
    }
    if (steer) y += "  steering_rate_radps: " + yaml_number(d.steering_rate_limit_radps) + "\n";
  }
  y += "effects: {}\n";
  return y;
}

}  // namespace

GeneratedRun generate(const RunSpec& spec) {
  const std::vector<Row> rows = simulate(spec);
  return {run_log_text(spec, rows), model_text(spec), expected_effects(spec),
          hidden_state_text(spec, rows), largest_driving_servo_error_rad(rows)};
}

namespace {

double parse_value(const std::string& assignment, const std::string& text) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v)) {
    throw std::invalid_argument(assignment + ": '" + text + "' is not a number");
  }
  return v;
}

void set_indexed(std::vector<double>& v, std::size_t n, double identity, std::size_t index,
                 double value) {
  if (v.size() < n) v.resize(n, identity);
  v[index] = value;
}

}  // namespace

void set_truth(RunSpec& spec, const std::string& assignment) {
  const auto eq = assignment.find('=');
  const auto dot = assignment.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq) {
    throw std::invalid_argument(assignment + ": expected NAME.PARAM=VALUE");
  }
  const std::string name = assignment.substr(0, dot);
  const std::string key = assignment.substr(dot + 1, eq - dot - 1);
  const double value = parse_value(assignment, assignment.substr(eq + 1));
  const Design d = design(spec.design);
  const bool swpc = d.drive == Drive::kSwpc;
  const std::size_t n = d.wheel_count();
  Truth& t = spec.truth;
  // Per-wheel keys: left/right (differential) or module_<i> (swpc).
  const auto wheel_index = [&](const std::string& suffix) -> std::size_t {
    if (!swpc && key == "left" + suffix) return 0;
    if (!swpc && key == "right" + suffix) return 1;
    if (swpc && key.rfind("module_", 0) == 0 && key.size() > 7 + suffix.size() &&
        key.compare(key.size() - suffix.size(), suffix.size(), suffix) == 0) {
      const std::string digits = key.substr(7, key.size() - 7 - suffix.size());
      char* end = nullptr;
      const long i = std::strtol(digits.c_str(), &end, 10);
      if (*end == '\0' && i >= 1 && static_cast<std::size_t>(i) <= n &&
          std::to_string(i) == digits) {
        return static_cast<std::size_t>(i - 1);
      }
    }
    throw std::invalid_argument(assignment + ": unknown parameter for the " + d.name + " robot");
  };
  const std::map<std::string, double*> scalars = {
      {"gyro_bias.bias_rad_s", &t.gyro_bias_rad_s},
      {"gyro_scale.scale", &t.gyro_scale},
      {"sensor_latency.delay_s", &t.sensor_delay_s},
      {"actuator_lag.time_constant_s", &t.actuator_lag_s},
      {"accel_limit.linear_mps2", &t.linear_accel_limit_mps2},
      {"accel_limit.angular_radps2", &t.angular_accel_limit_radps2},
      {"tyre.stiffness_per_load", &t.tyre_stiffness_per_load},
      {"tyre.friction", &t.friction_coefficient},
      {"steering.friction_nm", &t.steering_friction_nm},
      {"mocap.latency_s", &t.mocap_latency_s},
      {"mocap.clock_rate", &t.mocap_clock_rate},
      {"mocap.marker_x_m", &t.marker_x_m},
      {"mocap.marker_y_m", &t.marker_y_m},
      {"mocap.marker_yaw_rad", &t.marker_yaw_rad},
  };
  const std::string full = name + "." + key;
  if (const auto it = scalars.find(full); it != scalars.end()) {
    *it->second = value;
  } else if (!swpc && full == "track_width.scale") {
    t.track_width_scale = value;
  } else if (swpc && full == "steering_lag.time_constant_s") {
    t.steering_lag_s = value;
  } else if (swpc && full == "steering_rate_limit.radps") {
    t.steering_rate_limit_radps = value;
  } else if (name == "wheel_radius") {
    set_indexed(t.wheel_radius_scale, n, 1.0, wheel_index("_scale"), value);
  } else if (swpc && name == "caster_offset") {
    set_indexed(t.caster_offset_scale, n, 1.0, wheel_index("_scale"), value);
  } else if (swpc && name == "steering_offset") {
    set_indexed(t.steering_offset_rad, n, 0.0, wheel_index("_rad"), value);
  } else {
    throw std::invalid_argument(assignment + ": not a parameter of the " + d.name +
                                " robot (see swivel-second-run --help)");
  }
}

}  // namespace swivel::second
