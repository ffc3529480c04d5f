// SPDX-License-Identifier: Apache-2.0
#include "calibrate.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numbers>
#include <string>

#include "client.hpp"
#include "format.hpp"
#include "request.hpp"
#include "swivel.h"
#include "swivel/dds/topics.hpp"

namespace swivel::ctl {
namespace {

using Seconds = std::chrono::duration<double>;

struct CalibrateOptions {
  std::string action;
  std::string robot;
  double timeout_s = 3.0;
  std::uint32_t domain_id = 0;
  bool follow = true;
  bool json = false;
};

struct LastStatus {
  std::string status;
  bool received = false;
};

bool terminal(const std::string& status) {
  return status == "done" || status == "failed" || status == "cancelled" || status == "idle";
}

void print_modules(const swivel_msg_CalibrationResult& s) {
  if (s.modules._length == 0) return;
  constexpr double kRadToDeg = 180.0 / std::numbers::pi;
  std::printf("%-6s %22s %22s %20s %20s %20s\n", "MODULE", "x [mm]", "y [mm]", "delta [deg]",
              "d [mm]", "r [mm]");
  for (std::uint32_t i = 0; i < s.modules._length; ++i) {
    const auto& m = s.modules._buffer[i];
    std::printf(
        "%-6u %10.3f +- %8.3f %10.3f +- %8.3f %8.4f +- %7.4f %8.3f +- %7.3f %8.3f +- %7.3f\n",
        i + 1, m.x_m * 1e3, m.sigma_x_m * 1e3, m.y_m * 1e3, m.sigma_y_m * 1e3,
        m.delta_rad * kRadToDeg, m.sigma_delta_rad * kRadToDeg, m.d_m * 1e3, m.sigma_d_m * 1e3,
        m.r_m * 1e3, m.sigma_r_m * 1e3);
  }
}

int run_calibrate(const CalibrateOptions& o) {
  Client client(o.domain_id);
  const std::string robot = resolve_robot(client, o.robot, Seconds(o.timeout_s));
  const dds_entity_t results =
      client.reader(&swivel_msg_CalibrationResult_desc, dds::kCalibrationResultTopic);
  // The daemon answers first; progress and results follow as CalibrationResult samples,
  // which the reader above already receives.
  const Answer answer = send_request(client, robot, "calibrate", o.action, Seconds(o.timeout_s));
  if (!answer.ok) {
    std::cout << robot << ": calibrate " << o.action << ": " << answer.text << '\n';
    return 1;
  }

  // `start` follows progress until the result (analysis included); the others print the
  // daemon's answer (cancel: until the robot has stopped).
  const bool follow = o.action == "start" ? o.follow : o.action == "cancel";
  LastStatus last;
  const Seconds gap(follow ? std::max(o.timeout_s, 10.0) : o.timeout_s);
  for (;;) {
    if (!client.wait_for_data({results}, gap)) {
      if (interrupted()) return 130;
      std::cerr << "swivelctl: robot '" << robot << "' sent no calibration result within "
                << seconds_text(gap) << (last.received ? " (last status: " + last.status + ")" : "")
                << "\n";
      return 1;
    }
    bool stop = false;
    Client::take(results, [&](const void* p) {
      const auto& s = *static_cast<const swivel_msg_CalibrationResult*>(p);
      if (stop || robot != (s.robot_id != nullptr ? s.robot_id : "")) return;
      last.received = true;
      last.status = s.status != nullptr ? s.status : "";
      std::cout << (o.json ? to_json(s).dump() : to_line(s)) << '\n';
      if (!o.json && last.status == "done") print_modules(s);
      stop = !follow || terminal(last.status);
    });
    std::cout.flush();
    if (stop) break;
  }
  if (o.action == "status") return 0;
  if (o.action == "cancel") return last.status == "cancelled" || last.status == "idle" ? 0 : 1;
  return !follow ? (last.status == "running" ? 0 : 1) : (last.status == "done" ? 0 : 1);
}

}  // namespace

void add_calibrate_command(CLI::App& app) {
  auto options = std::make_shared<CalibrateOptions>();
  CLI::App* sub = app.add_subcommand(
      "calibrate", "start, cancel or query the calibration procedure of a daemon");
  sub->add_option("action", options->action, "start | cancel | status")
      ->required()
      ->check(CLI::IsMember({"start", "cancel", "status"}));
  sub->add_option("--robot", options->robot, "robot id (default: the only one)");
  sub->add_option("--timeout", options->timeout_s, "seconds to wait for an answer")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--domain", options->domain_id, "DDS domain id")->capture_default_str();
  sub->add_flag("!--no-follow", options->follow,
                "start: return once the daemon accepted instead of following to the result");
  sub->add_flag("--json", options->json, "one JSON object per sample");
  sub->callback([options] {
    install_signal_handlers();
    int code = 1;
    try {
      code = run_calibrate(*options);
    } catch (const std::exception& e) {
      std::cerr << "swivelctl: " << e.what() << '\n';
    }
    throw CLI::RuntimeError(code);
  });
}

}  // namespace swivel::ctl
