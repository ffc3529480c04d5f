// SPDX-License-Identifier: Apache-2.0
#include "swivel/daemon/daemon_config.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <utility>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::daemon {

PluginConfig& PluginConfig::operator=(const PluginConfig& other) {
  if (this == &other) return *this;
  plugin = other.plugin;
  params.reset(other.params);
  params_path = other.params_path;
  where = other.where;
  return *this;
}

// NOLINTNEXTLINE(performance-noexcept-move-constructor,bugprone-exception-escape): see the header
PluginConfig& PluginConfig::operator=(PluginConfig&& other) {
  plugin = std::move(other.plugin);
  params.reset(other.params);
  params_path = std::move(other.params_path);
  where = std::move(other.where);
  return *this;
}

namespace {

std::string resolve(const std::string& dir, const std::string& path) {
  if (path.empty() || path.front() == '/' || dir.empty()) return path;
  return dir + "/" + path;
}

std::string directory_of(const std::string& path) {
  const auto slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

bool valid_plugin_name(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

PluginConfig read_plugin(ParamReader& top, const std::string& section) {
  if (!top.has(section)) top.fail("", "missing required key '" + section + "'");
  ParamReader r = top.child(section);
  PluginConfig p;
  p.plugin = r.string("plugin");
  p.where = r.where("plugin");
  if (!valid_plugin_name(p.plugin)) {
    r.fail("plugin", "expected a plugin name (lower case, digits, '_'), got '" + p.plugin + "'");
  }
  p.params = r.child("params").node();
  p.params_path = section + ".params";
  r.finish();
  return p;
}

std::vector<ScriptStep> read_script(ParamReader& command) {
  const YAML::Node seq = command.sequence("script");
  std::vector<ScriptStep> script;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    ParamReader s = command.element(seq, "script", i);
    ScriptStep step;
    step.twist.vx_mps = s.number_or("vx_mps", 0.0, -10.0, 10.0);
    step.twist.vy_mps = s.number_or("vy_mps", 0.0, -10.0, 10.0);
    step.twist.wz_radps = s.number_or("wz_radps", 0.0, -20.0, 20.0);
    step.duration_s = s.number("duration_s", 0.001, 86400.0);
    s.finish();
    script.push_back(step);
  }
  return script;
}

YAML::Node parse_yaml(const std::string& text, const std::string& file) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    std::string where = file;
    if (!e.mark.is_null()) {
      where += ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1);
    }
    throw ConfigError(where + ": invalid YAML: " + e.msg);
  }
}

}  // namespace

const std::vector<std::string>& log_level_names() {
  static const std::vector<std::string> names{"trace", "debug",    "info", "warn",
                                              "error", "critical", "off"};
  return names;
}

DaemonConfig parse_daemon_config(const std::string& yaml_text, const std::string& file,
                                 const std::string& config_dir) {
  const YAML::Node root = parse_yaml(yaml_text, file);
  ParamReader top(root, file, "");
  DaemonConfig c;
  c.file = file;
  c.config_dir = config_dir;

  ParamReader loop = top.child("loop");
  c.rate_hz = loop.number_or("rate_hz", c.rate_hz, 1.0, 10000.0);
  c.fifo_priority = loop.integer_or("fifo_priority", c.fifo_priority, 1, 99);
  c.realtime = loop.boolean_or("realtime", c.realtime);
  loop.finish();

  const std::string model = top.string("robot_model");
  c.robot_model_path = resolve(config_dir, model);
  {
    struct stat st {};
    if (::stat(c.robot_model_path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
      top.fail("robot_model", "cannot read robot model file '" + model + "' (looked for " +
                                  c.robot_model_path + ")");
    }
  }

  c.hardware = read_plugin(top, "hardware");
  c.drivetrain = read_plugin(top, "drivetrain");
  c.localization = read_plugin(top, "localization");
  // Optional: without it (or with `calibration:` left empty) calibrate requests are refused.
  if (const YAML::Node section = top.child("calibration").node();
      section.IsDefined() && !section.IsNull()) {
    c.calibration = read_plugin(top, "calibration");
  }

  ParamReader command = top.child("command");
  c.command.timeout_s = command.number_or("timeout_s", c.command.timeout_s, 0.001, 60.0);
  const std::string source = command.choice_or("source", "none", {"script", "none"});
  c.command.source = source == "script" ? CommandSource::kScript : CommandSource::kNone;
  c.command.script = read_script(command);
  command.finish();  // first, so that a misspelt `script:` is reported as such
  if (c.command.source == CommandSource::kScript && c.command.script.empty()) {
    command.fail("script", "expected a non-empty list of steps when source is 'script'");
  }

  ParamReader stop = top.child("controlled_stop");
  c.controlled_stop.linear_deceleration_mps2 = stop.number_or(
      "linear_deceleration_mps2", c.controlled_stop.linear_deceleration_mps2, 0.01, 100.0);
  c.controlled_stop.angular_deceleration_radps2 = stop.number_or(
      "angular_deceleration_radps2", c.controlled_stop.angular_deceleration_radps2, 0.01, 1000.0);
  stop.finish();

  ParamReader odometry = top.child("odometry");
  {
    // At least the one-cycle difference, at most what the loop's window holds.
    const double period_s = 1.0 / c.rate_hz;
    c.twist_window_s = odometry.number_or("twist_window_s", c.twist_window_s, 0.0, 1.0e3);
    if (c.twist_window_s < period_s * (1.0 - 1e-9) ||
        c.twist_window_s > 255.0 * period_s * (1.0 + 1e-9)) {
      std::ostringstream message;
      message << "expected a number of seconds in [" << period_s << ", " << 255.0 * period_s
              << "] (1 to 255 periods of loop.rate_hz), got " << c.twist_window_s;
      odometry.fail("twist_window_s", message.str());
    }
  }
  odometry.finish();

  const YAML::Node paths = top.sequence("plugin_path");
  for (std::size_t i = 0; i < paths.size(); ++i) {
    if (!paths[i].IsScalar() || paths[i].Scalar().empty()) {
      top.fail("plugin_path", "expected a list of directories, got a non-text entry at index " +
                                  std::to_string(i));
    }
    c.plugin_path.push_back(resolve(config_dir, paths[i].Scalar()));
  }

  ParamReader logging = top.child("logging");
  c.log_level = logging.choice_or("level", c.log_level, log_level_names());
  logging.finish();

  ParamReader status = top.child("status");
  c.status_period_s = status.number_or("period_s", c.status_period_s, 0.01, 3600.0);
  status.finish();

  // Reserved for the DDS bridge, which validates its own keys; here only its shape.
  c.dds = top.child("dds").node();

  top.finish();
  // Last, so that a typo in swiveld.yaml is reported before a problem in the model.
  c.robot = load_robot_model(c.robot_model_path);
  return c;
}

DaemonConfig load_daemon_config(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot read configuration file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_daemon_config(text.str(), path, directory_of(path));
}

}  // namespace swivel::daemon
