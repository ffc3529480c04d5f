// SPDX-License-Identifier: Apache-2.0
#include "format.hpp"

#include <cstdio>
#include <vector>

namespace swivel::ctl {

namespace {

std::string str(const char* s) { return s != nullptr ? s : ""; }

// " (cause)" after the fault name when the daemon reports one.
bool has_text(const char* s) { return s != nullptr && s[0] != '\0'; }
const char* detail_open(const char* detail) { return has_text(detail) ? " (" : ""; }
const char* detail_close(const char* detail) { return has_text(detail) ? ")" : ""; }

nlohmann::json timing(const swivel_msg_TimingStats& t) {
  return {{"p50_us", t.p50_us}, {"p99_us", t.p99_us}, {"p999_us", t.p999_us}, {"max_us", t.max_us}};
}

template <typename... Args>
std::string format(const char* fmt, Args... args) {
  std::vector<char> buffer(512);
  for (;;) {
    const int n = std::snprintf(buffer.data(), buffer.size(), fmt, args...);
    if (n < 0) return {};
    if (static_cast<std::size_t>(n) < buffer.size()) {
      return {buffer.data(), static_cast<std::size_t>(n)};
    }
    buffer.resize(static_cast<std::size_t>(n) + 1);
  }
}

}  // namespace

const char* mode_name(swivel_msg_LoopMode mode) {
  switch (mode) {
    case swivel_msg_LOOP_MODE_IDLE: return "idle";
    case swivel_msg_LOOP_MODE_VELOCITY: return "velocity";
    case swivel_msg_LOOP_MODE_CALIBRATION: return "calibration";
    case swivel_msg_LOOP_MODE_SAFE_STOP: return "safe_stop";
  }
  return "unknown";
}

nlohmann::json to_json(const swivel_msg_RobotState& s) {
  nlohmann::json j = {
      {"robot_id", str(s.robot_id)},
      {"cycle", s.cycle},
      {"stamp_s", s.stamp_s},
      {"ros_stamp", {{"sec", s.ros_stamp_sec}, {"nanosec", s.ros_stamp_nanosec}}},
      {"pose", {{"x_m", s.x_m}, {"y_m", s.y_m}, {"yaw_rad", s.yaw_rad}}},
      {"has_covariance", s.has_covariance},
      {"pose_covariance", std::vector<double>(s.pose_covariance, s.pose_covariance + 9)},
      {"twist", {{"vx_mps", s.vx_mps}, {"vy_mps", s.vy_mps}, {"wz_radps", s.wz_radps}}},
      {"has_twist_covariance", s.has_twist_covariance},
      {"twist_covariance", std::vector<double>(s.twist_covariance, s.twist_covariance + 9)},
      {"command",
       {{"vx_mps", s.cmd_vx_mps}, {"vy_mps", s.cmd_vy_mps}, {"wz_radps", s.cmd_wz_radps}}},
      {"gyro_wz_radps", s.gyro_wz_radps},
      {"odometry_residual", s.odometry_residual},
      {"localization_plugin", str(s.localization_plugin)},
      {"localization_swaps", s.localization_swaps},
      {"mode", mode_name(s.mode)},
      {"fault_code", s.fault_code},
      {"fault", str(s.fault_text)},
      {"fault_detail", str(s.fault_detail)},
      {"fault_count", s.fault_count}};
  if (s.has_truth) {
    j["truth"] = {{"x_m", s.truth_x_m}, {"y_m", s.truth_y_m}, {"yaw_rad", s.truth_yaw_rad}};
  }
  return j;
}

nlohmann::json to_json(const swivel_msg_ModuleStates& s) {
  nlohmann::json modules = nlohmann::json::array();
  for (std::uint32_t i = 0; i < s.modules._length; ++i) {
    const auto& m = s.modules._buffer[i];
    modules.push_back({{"steer_angle_rad", m.steer_angle_rad},
                       {"steer_rate_cmd_radps", m.steer_rate_cmd_radps},
                       {"wheel_rate_cmd_radps", m.wheel_rate_cmd_radps},
                       {"wheel_rate_meas_radps", m.wheel_rate_meas_radps}});
  }
  return {{"robot_id", str(s.robot_id)},
          {"cycle", s.cycle},
          {"stamp_s", s.stamp_s},
          {"modules", modules}};
}

nlohmann::json to_json(const swivel_msg_Diagnostics& s) {
  return {{"robot_id", str(s.robot_id)},
          {"stamp_s", s.stamp_s},
          {"uptime_s", s.uptime_s},
          {"loop_rate_hz", s.loop_rate_hz},
          {"measured_rate_hz", s.measured_rate_hz},
          {"lateness", timing(s.lateness)},
          {"cycle_time", timing(s.cycle_time)},
          {"cycles", s.cycles},
          {"overruns", s.overruns},
          {"fault_count", s.fault_count},
          {"fault_code", s.fault_code},
          {"fault", str(s.fault_text)},
          {"fault_detail", str(s.fault_detail)},
          {"commands_received", s.commands_received},
          {"commands_dropped", s.commands_dropped},
          {"plugins",
           {{"hardware", str(s.hardware_plugin)},
            {"drivetrain", str(s.drivetrain_plugin)},
            {"localization", str(s.localization_plugin)}}},
          {"robot_model", str(s.robot_model)},
          {"reload_count", s.reload_count},
          {"last_reload_ok", s.last_reload_ok},
          {"last_reload_result", str(s.last_reload_result)},
          {"restart_required", s.restart_required},
          {"publish_rate_hz", s.publish_rate_hz},
          {"achieved_publish_rate_hz", s.achieved_publish_rate_hz},
          {"dds_warnings", str(s.dds_warnings)}};
}

nlohmann::json to_json(const swivel_msg_CalibrationResult& s) {
  nlohmann::json modules = nlohmann::json::array();
  for (std::uint32_t i = 0; i < s.modules._length; ++i) {
    const auto& m = s.modules._buffer[i];
    modules.push_back({{"x_m", m.x_m},
                       {"y_m", m.y_m},
                       {"delta_rad", m.delta_rad},
                       {"d_m", m.d_m},
                       {"r_m", m.r_m},
                       {"sigma_x_m", m.sigma_x_m},
                       {"sigma_y_m", m.sigma_y_m},
                       {"sigma_delta_rad", m.sigma_delta_rad},
                       {"sigma_d_m", m.sigma_d_m},
                       {"sigma_r_m", m.sigma_r_m}});
  }
  return {{"robot_id", str(s.robot_id)}, {"stamp_s", s.stamp_s}, {"status", str(s.status)},
          {"progress", s.progress},      {"text", str(s.text)},  {"modules", modules}};
}

std::string to_line(const swivel_msg_RobotState& s) {
  return format(
      "%s t=%.3fs x=%.4fm y=%.4fm yaw=%.4frad vx=%.3fm/s vy=%.3fm/s wz=%.3frad/s mode=%s "
      "localization=%s fault=%s%s%s%s faults=%llu",
      str(s.robot_id).c_str(), s.stamp_s, s.x_m, s.y_m, s.yaw_rad, s.vx_mps, s.vy_mps, s.wz_radps,
      mode_name(s.mode), str(s.localization_plugin).c_str(), str(s.fault_text).c_str(),
      detail_open(s.fault_detail), str(s.fault_detail).c_str(), detail_close(s.fault_detail),
      static_cast<unsigned long long>(s.fault_count));
}

std::string to_line(const swivel_msg_ModuleStates& s) {
  std::string line = format("%s t=%.3fs", str(s.robot_id).c_str(), s.stamp_s);
  for (std::uint32_t i = 0; i < s.modules._length; ++i) {
    const auto& m = s.modules._buffer[i];
    line += format(" [%u steer=%.4frad wheel=%.3f/%.3frad/s]", i, m.steer_angle_rad,
                   m.wheel_rate_meas_radps, m.wheel_rate_cmd_radps);
  }
  return line;
}

std::string to_line(const swivel_msg_Diagnostics& s) {
  return format(
      "%s rate=%.1f/%.1fHz lateness p50/p99/p99.9/max=%.1f/%.1f/%.1f/%.1fus "
      "cycle p50/p99/p99.9/max=%.1f/%.1f/%.1f/%.1fus overruns=%llu fault=%s%s%s%s faults=%llu "
      "plugins=%s/%s/%s model=%s reloads=%u last_reload=%s%s publish=%.1f/%gHz%s%s",
      str(s.robot_id).c_str(), s.measured_rate_hz, s.loop_rate_hz, s.lateness.p50_us,
      s.lateness.p99_us, s.lateness.p999_us, s.lateness.max_us, s.cycle_time.p50_us,
      s.cycle_time.p99_us, s.cycle_time.p999_us, s.cycle_time.max_us,
      static_cast<unsigned long long>(s.overruns), str(s.fault_text).c_str(),
      detail_open(s.fault_detail), str(s.fault_detail).c_str(), detail_close(s.fault_detail),
      static_cast<unsigned long long>(s.fault_count), str(s.hardware_plugin).c_str(),
      str(s.drivetrain_plugin).c_str(), str(s.localization_plugin).c_str(),
      str(s.robot_model).c_str(), s.reload_count,
      s.reload_count == 0 ? "-" : (s.last_reload_ok ? "ok" : "rejected"),
      s.restart_required ? " (restart required)" : "", s.achieved_publish_rate_hz,
      s.publish_rate_hz,
      str(s.dds_warnings).empty() ? "" : " warnings: ", str(s.dds_warnings).c_str());
}

std::string to_line(const swivel_msg_CalibrationResult& s) {
  return format("%s status=%s progress=%.0f%% modules=%u %s", str(s.robot_id).c_str(),
                str(s.status).c_str(), 100.0 * s.progress, s.modules._length, str(s.text).c_str());
}

}  // namespace swivel::ctl
