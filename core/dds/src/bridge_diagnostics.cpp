// SPDX-License-Identifier: Apache-2.0
// The bridge's status reports, written by its publisher thread at dds.diagnostics_rate_hz:
// Swivel's Diagnostics (the daemon's sample with the bridge's own counters) and ROS 2's
// DiagnosticArray (one DiagnosticStatus, its level from the loop's mode and faults), and the
// DDS warnings both carry.
#include <spdlog/spdlog.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "bridge_entities.hpp"
#include "ros2_interfaces.h"
#include "swivel.h"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/cmd_vel_type_check.hpp"
#include "swivel/dds/sensor_inputs.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/rt/clock_offset.hpp"

namespace swivel::dds {

namespace {

swivel_msg_TimingStats to_msg(const TimingPercentiles& p) {
  return {p.p50_us, p.p99_us, p.p999_us, p.max_us};
}

}  // namespace

std::string DdsBridge::dds_warnings() const {
  std::string text = dds_->cmd_vel_check ? dds_->cmd_vel_check->warning() : std::string();
  if (publish_rate_short_.load()) {
    if (!text.empty()) text += "; ";
    text += fmt::format("states published at {:.1f} Hz of {:.1f} Hz attainable ",
                        achieved_publish_rate_hz_.load(), attainable_publish_rate_hz_.load()) +
            fmt::format("(dds.publish_rate_hz: {:g})", options_.publish_rate_hz);
  }
  return text;
}

void DdsBridge::publish_diagnostics(const DiagnosticsSample& d) {
  swivel_msg_Diagnostics msg{};
  msg.robot_id = c_str(robot_id_);
  msg.stamp_s = monotonic_s();
  msg.uptime_s = d.uptime_s;
  msg.loop_rate_hz = d.loop_rate_hz;
  msg.measured_rate_hz = d.measured_rate_hz;
  msg.lateness = to_msg(d.lateness);
  msg.cycle_time = to_msg(d.cycle_time);
  msg.cycles = d.cycles;
  msg.overruns = d.overruns;
  msg.fault_count = d.fault_count;
  msg.fault_code = static_cast<std::uint16_t>(d.fault);
  msg.fault_text = c_str(fault_code_name(d.fault));
  msg.fault_detail = c_str(d.fault_detail);
  msg.commands_received = commands_received_.load(std::memory_order_relaxed);
  msg.commands_dropped = commands_dropped_.load(std::memory_order_relaxed);
  msg.hardware_plugin = c_str(d.hardware_plugin);
  msg.drivetrain_plugin = c_str(d.drivetrain_plugin);
  msg.localization_plugin = c_str(d.localization_plugin);
  msg.robot_model = c_str(d.robot_model);
  msg.reload_count = d.reload_count;
  msg.last_reload_ok = d.last_reload_ok;
  msg.last_reload_result = c_str(d.last_reload_result);
  msg.restart_required = d.restart_required;
  msg.publish_rate_hz = options_.publish_rate_hz;
  msg.achieved_publish_rate_hz = achieved_publish_rate_hz_.load();
  const std::string warnings = dds_warnings();
  msg.dds_warnings = c_str(warnings);
  check(dds_write(dds_->diagnostics_writer, &msg), "dds_write(diagnostics)");
  if (dds_->ros2_diagnostics_writer != 0) publish_ros2_diagnostics(d, warnings);
}

// One DiagnosticStatus for the robot: ERROR while the loop holds it in a safe stop, WARN for
// a transient fault (a command timeout, a rejected command) or a configuration that did not
// apply, OK otherwise; the values are Diagnostics' fields as text.
void DdsBridge::publish_ros2_diagnostics(const DiagnosticsSample& d,
                                         const std::string& dds_warnings) {
  constexpr std::uint8_t kOk = 0;
  constexpr std::uint8_t kWarn = 1;
  constexpr std::uint8_t kError = 2;
  std::uint8_t level = kOk;
  std::string message = "running";
  if (d.mode == LoopMode::kSafeStop) {
    level = kError;
  } else if (d.fault != FaultCode::kNone || !d.last_reload_ok || d.restart_required ||
             !dds_warnings.empty()) {
    level = kWarn;
  }
  if (d.fault != FaultCode::kNone) {
    message = std::string(d.mode == LoopMode::kSafeStop ? "safe stop: " : "") +
              fault_code_name(d.fault) +
              (d.fault_detail.empty() ? "" : " (" + d.fault_detail + ")");
  } else if (!d.last_reload_ok) {
    message = "running; last reload rejected";
  } else if (d.restart_required) {
    message = "running; a changed setting needs a restart";
  } else if (!dds_warnings.empty()) {
    message = "running; " + dds_warnings;
  }
  const char* mode = d.mode == LoopMode::kIdle          ? "idle"
                     : d.mode == LoopMode::kVelocity    ? "velocity"
                     : d.mode == LoopMode::kCalibration ? "calibration"
                                                        : "safe_stop";
  std::vector<std::pair<std::string, std::string>> values{
      {"mode", mode},
      {"fault", fault_code_name(d.fault)},
      {"fault_detail", d.fault_detail},
      {"fault_count", std::to_string(d.fault_count)},
      {"uptime_s", fmt::format("{:.1f}", d.uptime_s)},
      {"loop_rate_hz", fmt::format("{:g}", d.loop_rate_hz)},
      {"measured_rate_hz", fmt::format("{:.1f}", d.measured_rate_hz)},
      {"lateness_p99_us", fmt::format("{:.1f}", d.lateness.p99_us)},
      {"lateness_max_us", fmt::format("{:.1f}", d.lateness.max_us)},
      {"cycle_time_p99_us", fmt::format("{:.1f}", d.cycle_time.p99_us)},
      {"cycle_time_max_us", fmt::format("{:.1f}", d.cycle_time.max_us)},
      {"cycles", std::to_string(d.cycles)},
      {"overruns", std::to_string(d.overruns)},
      {"hardware_plugin", d.hardware_plugin},
      {"drivetrain_plugin", d.drivetrain_plugin},
      {"localization_plugin", d.localization_plugin},
      {"robot_model", d.robot_model},
      {"commands_received", std::to_string(commands_received_.load(std::memory_order_relaxed))},
      {"commands_dropped", std::to_string(commands_dropped_.load(std::memory_order_relaxed))},
      {"commands_stale", std::to_string(commands_stale_.load(std::memory_order_relaxed))},
      {"publish_failures", std::to_string(publish_failures_.load(std::memory_order_relaxed))},
      {"reload_count", std::to_string(d.reload_count)},
      {"last_reload", d.last_reload_result},
      {"restart_required", d.restart_required ? "true" : "false"},
      {"publish_rate_hz", fmt::format("{:g}", options_.publish_rate_hz)},
      {"achieved_publish_rate_hz", fmt::format("{:.1f}", achieved_publish_rate_hz_.load())},
      {"cmd_vel_type", options_.ros2.cmd_vel_stamped ? "geometry_msgs/msg/TwistStamped"
                                                     : "geometry_msgs/msg/Twist"},
      {"dds_warnings", dds_warnings}};
  if (dds_->sensors) {
    // The ROS 2 sensor topics' samples: a driver whose samples are all rejected shows here
    // before its silence stops the robot.
    const SensorCounters sensors = dds_->sensors->counters();
    if (options_.ros2.imu.enabled) {
      values.emplace_back("imu_samples", std::to_string(sensors.imu_received));
      values.emplace_back("imu_samples_rejected", std::to_string(sensors.imu_rejected));
    }
    if (options_.ros2.mocap_pose.enabled) {
      values.emplace_back("mocap_pose_samples", std::to_string(sensors.mocap_poses_received));
      values.emplace_back("mocap_pose_samples_rejected",
                          std::to_string(sensors.mocap_poses_rejected));
    }
    values.emplace_back("sensor_samples_dropped", std::to_string(sensors.dropped));
  }
  std::vector<diagnostic_msgs_msg_dds__KeyValue_> pairs(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    pairs[i].key = c_str(values[i].first);
    pairs[i].value = c_str(values[i].second);
  }
  const std::string name = "swiveld: " + robot_id_;
  diagnostic_msgs_msg_dds__DiagnosticStatus_ status{};
  status.level = level;
  status.name = c_str(name);
  status.message = c_str(message);
  status.hardware_id = c_str(robot_id_);
  borrow(status.values, pairs.data(), static_cast<std::uint32_t>(pairs.size()));

  diagnostic_msgs_msg_dds__DiagnosticArray_ array{};
  const rt::RosTime now = rt::to_ros_time(realtime_now_ns());
  array.header.stamp.sec = now.sec;
  array.header.stamp.nanosec = now.nanosec;
  array.header.frame_id = c_str("");
  borrow(array.status, &status, 1);
  check(dds_write(dds_->ros2_diagnostics_writer, &array), "dds_write(ros2 diagnostics)");
}

}  // namespace swivel::dds
