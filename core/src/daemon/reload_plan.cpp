// SPDX-License-Identifier: Apache-2.0
#include "reload_plan.hpp"

#include <yaml-cpp/yaml.h>

namespace swivel::daemon {
namespace {

std::string dump(const YAML::Node& node) {
  if (!node || node.IsNull()) return "";
  YAML::Emitter out;
  out << node;
  return out.c_str();
}

bool same_slot(const PluginConfig& a, const PluginConfig& b) {
  return a.plugin == b.plugin && dump(a.params) == dump(b.params);
}

bool same_script(const std::vector<ScriptStep>& a, const std::vector<ScriptStep>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].duration_s != b[i].duration_s || a[i].twist.vx_mps != b[i].twist.vx_mps ||
        a[i].twist.vy_mps != b[i].twist.vy_mps || a[i].twist.wz_radps != b[i].twist.wz_radps) {
      return false;
    }
  }
  return true;
}

}  // namespace

std::string comma_list(const std::vector<std::string>& items) {
  std::string text;
  for (const auto& item : items) text += (text.empty() ? "" : ", ") + item;
  return text;
}

ReloadPlan plan_reload(const DaemonConfig& running, std::string_view running_model_text,
                       const DaemonConfig& fresh, std::string_view fresh_model_text) {
  ReloadPlan plan;
  auto& restart = plan.restart;
  if (fresh.rate_hz != running.rate_hz) restart.emplace_back("loop.rate_hz");
  if (fresh.fifo_priority != running.fifo_priority) restart.emplace_back("loop.fifo_priority");
  if (fresh.realtime != running.realtime) restart.emplace_back("loop.realtime");
  if (!same_slot(fresh.hardware, running.hardware)) restart.emplace_back("hardware");
  if (!same_slot(fresh.drivetrain, running.drivetrain)) restart.emplace_back("drivetrain");
  if (fresh.command.timeout_s != running.command.timeout_s ||
      fresh.command.source != running.command.source ||
      !same_script(fresh.command.script, running.command.script)) {
    restart.emplace_back("command");
  }
  if (fresh.plugin_path != running.plugin_path) restart.emplace_back("plugin_path");
  if (dump(fresh.dds) != dump(running.dds)) restart.emplace_back("dds");
  if (!same_slot(fresh.calibration, running.calibration)) restart.emplace_back("calibration");
  if (fresh.controlled_stop.linear_deceleration_mps2 !=
          running.controlled_stop.linear_deceleration_mps2 ||
      fresh.controlled_stop.angular_deceleration_radps2 !=
          running.controlled_stop.angular_deceleration_radps2) {
    restart.emplace_back("controlled_stop");
  }
  if (fresh.twist_window_s != running.twist_window_s) restart.emplace_back("odometry");
  plan.swap_localization = !same_slot(fresh.localization, running.localization);
  plan.swap_model =
      fresh.robot_model_path != running.robot_model_path || fresh_model_text != running_model_text;
  if (fresh.log_level != running.log_level) plan.log_level = fresh.log_level;
  if (fresh.status_period_s != running.status_period_s) {
    plan.status_period_s = fresh.status_period_s;
  }
  return plan;
}

std::string model_swap_problem(const RobotModel& running, const RobotModel& fresh) {
  const auto kind = [](DrivetrainKind k) {
    return k == DrivetrainKind::kSwpc ? "swpc" : "differential";
  };
  if (fresh.drivetrain != running.drivetrain) {
    return std::string("drivetrain: ") + kind(fresh.drivetrain) + ", but the running robot is " +
           kind(running.drivetrain) + " (a new drivetrain kind needs a restart)";
  }
  if (fresh.module_count() != running.module_count()) {
    return std::to_string(fresh.module_count()) + " modules, but the running robot has " +
           std::to_string(running.module_count()) + " (a new module count needs a restart)";
  }
  if (fresh.name != running.name) {
    return "name: '" + fresh.name + "', but the running robot is '" + running.name +
           "' (its DDS topics are keyed by the name: a new name needs a restart)";
  }
  return "";
}

std::string describe_reload(const std::vector<std::string>& applied,
                            const std::vector<std::string>& restart) {
  std::string text = applied.empty() ? "no live change" : "applied " + comma_list(applied);
  if (!restart.empty()) text += "; needs a restart: " + comma_list(restart);
  return text;
}

}  // namespace swivel::daemon
