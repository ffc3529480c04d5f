// SPDX-License-Identifier: Apache-2.0
// swivelctl: a command-line client of running swiveld daemons over DDS.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <thread>

#include "calibrate.hpp"
#include "client.hpp"
#include "format.hpp"
#include "record.hpp"
#include "request.hpp"
#include "swivel.h"
#include "swivel/cli/command_line.hpp"
#include "swivel/clock.hpp"
#include "swivel/dds/topics.hpp"

namespace swivel::ctl {

namespace {

using Seconds = std::chrono::duration<double>;

struct CommonOptions {
  std::string robot;
  double timeout_s = 3.0;
  std::uint32_t domain_id = 0;
};

// Reads samples of one topic and prints them until `count` were printed (0: forever).
template <typename Msg>
int echo_topic(Client& client, const dds_topic_descriptor_t* desc, const char* topic,
               const CommonOptions& common, int count, bool json) {
  const dds_entity_t reader = client.reader(desc, topic);
  int printed = 0;
  while (count == 0 || printed < count) {
    if (!client.wait_for_data({reader}, Seconds(common.timeout_s))) {
      if (interrupted()) return printed > 0 ? 0 : 130;
      std::cerr << "swivelctl: no " << topic << " sample"
                << (common.robot.empty() ? "" : " from robot '" + common.robot + "'") << " within "
                << seconds_text(Seconds(common.timeout_s))
                << (printed == 0 ? " (is swiveld running on this DDS domain? " +
                                       dds::describe_tool_config() + ")"
                                 : "")
                << "\n";
      return 1;
    }
    Client::take(reader, [&](const void* p) {
      const auto& msg = *static_cast<const Msg*>(p);
      if (!common.robot.empty() && common.robot != msg.robot_id) return;
      if (count != 0 && printed >= count) return;
      std::cout << (json ? to_json(msg).dump() : to_line(msg)) << '\n';
      ++printed;
    });
    std::cout.flush();
  }
  return 0;
}

int run_echo(const std::string& what, const CommonOptions& common, int count, bool json) {
  Client client(common.domain_id);
  if (what == "state") {
    return echo_topic<swivel_msg_RobotState>(client, &swivel_msg_RobotState_desc,
                                             dds::kRobotStateTopic, common, count, json);
  }
  if (what == "modules") {
    return echo_topic<swivel_msg_ModuleStates>(client, &swivel_msg_ModuleStates_desc,
                                               dds::kModuleStatesTopic, common, count, json);
  }
  if (what == "diagnostics") {
    return echo_topic<swivel_msg_Diagnostics>(client, &swivel_msg_Diagnostics_desc,
                                              dds::kDiagnosticsTopic, common, count, json);
  }
  return echo_topic<swivel_msg_CalibrationResult>(client, &swivel_msg_CalibrationResult_desc,
                                                  dds::kCalibrationResultTopic, common, count,
                                                  json);
}

int run_drive(double vx, double vy, double wz, double for_s, double rate_hz,
              const CommonOptions& common) {
  Client client(common.domain_id);
  const std::string robot = resolve_robot(client, common.robot, Seconds(common.timeout_s));
  const dds_entity_t writer =
      client.writer(&swivel_msg_VelocityCommand_desc, dds::kVelocityCommandTopic);
  if (!Client::wait_for_match(writer, Seconds(common.timeout_s))) {
    std::cerr << "swivelctl: robot '" << robot << "' publishes state but no velocity command "
              << "reader matched within " << seconds_text(Seconds(common.timeout_s)) << "\n";
    return 1;
  }
  std::cerr << "driving " << robot << " at vx=" << vx << " m/s vy=" << vy << " m/s wz=" << wz
            << " rad/s " << (for_s > 0 ? "for " + seconds_text(Seconds(for_s)) : "until Ctrl-C")
            << "\n";

  swivel_msg_VelocityCommand command{};
  std::string id = robot;
  command.robot_id = id.data();
  auto send = [&](double x, double y, double z) {
    command.stamp_s = swivel::monotonic_s();
    ++command.sequence_number;
    command.vx_mps = x;
    command.vy_mps = y;
    command.wz_radps = z;
    dds::check(dds_write(writer, &command), "dds_write(velocity command)");
  };
  const auto period =
      std::chrono::duration_cast<std::chrono::steady_clock::duration>(Seconds(1.0 / rate_hz));
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  while (!interrupted() &&
         (for_s <= 0 || std::chrono::steady_clock::now() - start < Seconds(for_s))) {
    send(vx, vy, wz);
    next += period;
    std::this_thread::sleep_until(next);
  }
  // Stop explicitly rather than waiting for the daemon's command timeout.
  send(0.0, 0.0, 0.0);
  dds_wait_for_acks(writer, DDS_SECS(1));
  return 0;
}

struct RobotSummary {
  std::optional<swivel_msg_RobotState> state;
  std::string localization, fault;
  std::optional<nlohmann::json> diagnostics;
};

int run_status(const CommonOptions& common, bool json) {
  Client client(common.domain_id);
  const dds_entity_t states = client.reader(&swivel_msg_RobotState_desc, dds::kRobotStateTopic);
  const dds_entity_t diagnostics =
      client.reader(&swivel_msg_Diagnostics_desc, dds::kDiagnosticsTopic);
  std::map<std::string, RobotSummary> robots;
  const auto start = std::chrono::steady_clock::now();
  const Seconds timeout(common.timeout_s);
  // Listen at least this long so that every daemon of a fleet is heard, then stop as soon
  // as each robot seen has reported both state and diagnostics.
  const Seconds settle(std::min(1.5, common.timeout_s));
  for (;;) {
    const auto elapsed = std::chrono::steady_clock::now() - start;
    bool complete = !robots.empty();
    for (const auto& [id, r] : robots) complete = complete && r.state && r.diagnostics;
    if ((complete && elapsed >= settle) || elapsed >= timeout || interrupted()) break;
    client.wait_for_data({states, diagnostics}, std::min<Seconds>(timeout - elapsed, Seconds(0.1)));
    Client::take(states, [&](const void* p) {
      const auto& s = *static_cast<const swivel_msg_RobotState*>(p);
      if (!common.robot.empty() && common.robot != s.robot_id) return;
      auto& r = robots[s.robot_id];
      r.state = s;
      r.state->robot_id = nullptr;  // loaned strings: keep copies instead
      r.state->localization_plugin = nullptr;
      r.state->fault_text = nullptr;
      r.state->fault_detail = nullptr;
      r.localization = s.localization_plugin;
      r.fault = s.fault_text;
    });
    Client::take(diagnostics, [&](const void* p) {
      const auto& d = *static_cast<const swivel_msg_Diagnostics*>(p);
      if (!common.robot.empty() && common.robot != d.robot_id) return;
      robots[d.robot_id].diagnostics = to_json(d);
    });
  }
  if (robots.empty()) {
    std::cerr << "swivelctl: no swiveld answered within " << seconds_text(timeout)
              << (common.robot.empty() ? "" : " as robot '" + common.robot + "'")
              << " (DDS configuration: " << dds::describe_tool_config() << ")\n";
    return 1;
  }
  nlohmann::json all = nlohmann::json::object();
  if (!json) {
    std::printf("%-16s %-10s %-14s %-20s %-18s %10s %12s %12s %9s %13s  %s\n", "ROBOT", "MODE",
                "LOCALIZATION", "FAULT", "PLUGINS", "RATE_HZ", "LATE_P99_US", "CYCLE_P99_US",
                "OVERRUNS", "PUB_HZ", "POSE (x m, y m, yaw rad)");
  }
  for (const auto& [id, r] : robots) {
    nlohmann::json entry;
    entry["robot_id"] = id;
    if (r.state) {
      entry["mode"] = mode_name(r.state->mode);
      entry["localization_plugin"] = r.localization;
      entry["fault"] = r.fault;
      entry["fault_count"] = r.state->fault_count;
      entry["pose"] = {{"x_m", r.state->x_m}, {"y_m", r.state->y_m}, {"yaw_rad", r.state->yaw_rad}};
    }
    if (r.diagnostics) entry["diagnostics"] = *r.diagnostics;
    all[id] = entry;
    if (json) continue;
    const nlohmann::json d = r.diagnostics.value_or(nlohmann::json::object());
    auto num = [&](const char* a, const char* b = nullptr) {
      if (!d.contains(a)) return std::string("-");
      const auto& v = b != nullptr ? d[a][b] : d[a];
      char text[32];
      std::snprintf(text, sizeof text, "%.1f", v.get<double>());
      return std::string(text);
    };
    const std::string plugins = r.diagnostics ? d["plugins"]["hardware"].get<std::string>() + "/" +
                                                    d["plugins"]["drivetrain"].get<std::string>()
                                              : "-";
    const std::string pose = r.state ? std::to_string(r.state->x_m).substr(0, 7) + ", " +
                                           std::to_string(r.state->y_m).substr(0, 7) + ", " +
                                           std::to_string(r.state->yaw_rad).substr(0, 7)
                                     : "-";
    // States published per second against dds.publish_rate_hz, e.g. "859.2/1000".
    const std::string publish =
        d.contains("publish_rate_hz")
            ? num("achieved_publish_rate_hz") + "/" +
                  std::to_string(std::lround(d["publish_rate_hz"].get<double>()))
            : "-";
    std::printf(
        "%-16s %-10s %-14s %-20s %-18s %10s %12s %12s %9s %13s  %s\n", id.c_str(),
        r.state ? mode_name(r.state->mode) : "-", r.state ? r.localization.c_str() : "-",
        r.state ? r.fault.c_str() : "-", plugins.c_str(), num("measured_rate_hz").c_str(),
        num("lateness", "p99_us").c_str(), num("cycle_time", "p99_us").c_str(),
        d.contains("overruns") ? std::to_string(d["overruns"].get<std::uint64_t>()).c_str() : "-",
        publish.c_str(), pose.c_str());
    // What the daemon's DDS side found wrong (a cmd_vel publisher of the other type, a
    // publish rate short of the configured one), on its own line under the robot's row.
    const std::string warnings = d.value("dds_warnings", std::string());
    if (!warnings.empty()) std::printf("  %s: %s\n", id.c_str(), warnings.c_str());
  }
  if (json) std::cout << all.dump() << '\n';
  return 0;
}

// One request, its answer on stdout ("<robot>: <answer>"); 1 when refused.
template <typename Send>
int run_request(const CommonOptions& common, const Send& send,
                const std::function<std::string(const Answer&)>& line) {
  Client client(common.domain_id);
  const std::string robot = resolve_robot(client, common.robot, Seconds(common.timeout_s));
  const Answer answer = send(client, robot, Seconds(common.timeout_s));
  std::cout << robot << ": " << line(answer) << '\n';
  return answer.ok ? 0 : 1;
}

int run_reload(const CommonOptions& common) {
  return run_request(
      common,
      [](Client& client, const std::string& robot, Seconds timeout) {
        return send_request(client, robot, "reload", "", timeout);
      },
      [](const Answer& a) {
        return std::string("reload ") + (a.ok ? "applied" : "rejected") +
               (a.text.empty() ? "" : ": " + a.text);
      });
}

int run_clear(const CommonOptions& common) {
  return run_request(
      common,
      [](Client& client, const std::string& robot, Seconds timeout) {
        return send_request(client, robot, "clear", "", timeout);
      },
      [](const Answer& a) { return "clear: " + a.text; });
}

int run_set_pose(const PoseRequest& pose, const CommonOptions& common) {
  return run_request(
      common,
      [&](Client& client, const std::string& robot, Seconds timeout) {
        return send_set_pose(client, robot, pose, timeout);
      },
      [](const Answer& a) { return "set-pose: " + a.text; });
}

}  // namespace

}  // namespace swivel::ctl

namespace {

// The command line, parsed and run; main() catches what escapes the set-up.
int run_command_line(int argc, char** argv) {
  using namespace swivel::ctl;
  CLI::App app{
      "swivelctl: talk to running swiveld daemons over DDS.\n"
      "DDS configuration: CYCLONEDDS_URI when set, otherwise Swivel's loopback-only\n"
      "config/dds/loopback.xml (build tree) or <sysconfdir>/swivel/dds/loopback.xml\n"
      "(installed). Now: " +
      swivel::dds::describe_tool_config()};
  app.require_subcommand(1);
  CommonOptions common;
  auto add_common = [&](CLI::App* sub, bool robot) {
    if (robot) sub->add_option("--robot", common.robot, "robot id (default: the only one)");
    sub->add_option("--timeout", common.timeout_s, "seconds to wait for an answer")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    sub->add_option("--domain", common.domain_id, "DDS domain id")->capture_default_str();
  };

  std::string what = "state";
  int count = 0;
  bool json = false;
  CLI::App* echo = app.add_subcommand("echo", "print samples as they arrive");
  echo->add_option("topic", what, "state | modules | diagnostics | calibration")
      ->required()
      ->check(CLI::IsMember({"state", "modules", "diagnostics", "calibration"}));
  echo->add_option("--count", count, "stop after N samples (0: never)")
      ->check(CLI::NonNegativeNumber);
  echo->add_flag("--json", json, "one JSON object per line");
  add_common(echo, true);

  double vx = 0;
  double vy = 0;
  double wz = 0;
  double for_s = 0;
  double rate_hz = 20;
  CLI::App* drive = app.add_subcommand("drive", "send a body velocity command, then stop");
  drive->add_option("vx", vx, "forward velocity, m/s")->required();
  drive->add_option("vy", vy, "leftward velocity, m/s")->required();
  drive->add_option("wz", wz, "yaw rate, rad/s (counter-clockwise positive)")->required();
  drive->add_option("--for", for_s, "seconds to drive (0: until Ctrl-C)")->capture_default_str();
  drive->add_option("--rate-hz", rate_hz, "command rate, Hz")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  add_common(drive, true);

  CLI::App* status = app.add_subcommand("status", "summarise every daemon on the domain");
  status->add_flag("--json", json, "one JSON object keyed by robot id");
  add_common(status, true);

  CLI::App* reload = app.add_subcommand("reload", "ask a daemon to re-read its configuration");
  add_common(reload, true);

  CLI::App* clear = app.add_subcommand(
      "clear",
      "leave the active fault once its cause is gone (refused, with the cause, while "
      "it persists)");
  add_common(clear, true);

  PoseRequest pose;
  std::vector<double> sigma;
  CLI::App* set_pose = app.add_subcommand(
      "set-pose", "set the pose estimate through the active localization's hand-over");
  set_pose->add_option("x", pose.pose.x_m, "position x, m, world frame")->required();
  set_pose->add_option("y", pose.pose.y_m, "position y, m, world frame")->required();
  set_pose->add_option("yaw", pose.pose.yaw_rad, "heading, rad, counter-clockwise positive")
      ->required();
  set_pose
      ->add_option("--sigma", sigma,
                   "standard deviations SX_M SY_M SYAW_RAD (default: the localization keeps "
                   "its own uncertainty)")
      ->expected(3);
  add_common(set_pose, true);

  add_calibrate_command(app);
  add_record_command(app);

  if (const auto exit = swivel::cli::parse(app, argc, argv, "swivelctl")) return *exit;
  install_signal_handlers();
  try {
    if (*echo) return run_echo(what, common, count, json);
    if (*drive) {
      if (!std::isfinite(vx) || !std::isfinite(vy) || !std::isfinite(wz)) {
        std::cerr << "swivelctl: velocities must be finite\n";
        return swivel::cli::kUsageError;
      }
      return run_drive(vx, vy, wz, for_s, rate_hz, common);
    }
    if (*status) return run_status(common, json);
    if (*reload) return run_reload(common);
    if (*clear) return run_clear(common);
    if (*set_pose) {
      if (!std::isfinite(pose.pose.x_m) || !std::isfinite(pose.pose.y_m) ||
          !std::isfinite(pose.pose.yaw_rad)) {
        std::cerr << "swivelctl: x, y and yaw must be finite\n";
        return swivel::cli::kUsageError;
      }
      if (!sigma.empty()) {
        for (const double s : sigma) {
          if (!std::isfinite(s) || s < 0.0) {
            std::cerr << "swivelctl: --sigma: standard deviations must be finite and >= 0\n";
            return swivel::cli::kUsageError;
          }
        }
        pose.has_sigma = true;
        pose.sigma_x_m = sigma[0];
        pose.sigma_y_m = sigma[1];
        pose.sigma_yaw_rad = sigma[2];
      }
      return run_set_pose(pose, common);
    }
  } catch (const std::exception& e) {
    std::cerr << "swivelctl: " << e.what() << '\n';
    return 1;
  }
  return swivel::cli::kUsageError;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run_command_line(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "swivelctl: " << e.what() << '\n';
  } catch (...) {
    std::cerr << "swivelctl: unknown error\n";
  }
  return 1;
}
