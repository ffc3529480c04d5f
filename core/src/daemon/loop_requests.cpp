// SPDX-License-Identifier: Apache-2.0
#include "loop_requests.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>
#include <utility>

#include "hardware_lifecycle.hpp"
#include "swivel/clock.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {
namespace {

bool finite_pose(const PoseEstimate& p) {
  if (!std::isfinite(p.pose.x_m) || !std::isfinite(p.pose.y_m) || !std::isfinite(p.pose.yaw_rad)) {
    return false;
  }
  if (!p.has_covariance) return true;
  return std::ranges::all_of(p.covariance, [](double v) { return std::isfinite(v); });
}

std::string format(const char* pattern, double a, double b, double c) {
  char text[160];
  std::snprintf(text, sizeof text, pattern, a, b, c);
  return text;
}

}  // namespace

LoopRequests::LoopRequests(rt::ControlLoop& loop, Hardware& hardware, std::string hardware_plugin)
    : loop_(loop), hardware_(hardware), hardware_plugin_(std::move(hardware_plugin)) {}

bool LoopRequests::wait_for_reply(std::uint64_t id, rt::LoopReply& out) {
  // The loop answers at its next cycle; a second covers a stalled or very slow loop.
  const double deadline_s = monotonic_s() + 1.0;
  while (monotonic_s() < deadline_s && loop_.running()) {
    if (loop_.take_reply(out) && out.id == id) return true;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  return false;
}

dds::ReplySample LoopRequests::clear(std::uint64_t request_id) {
  dds::ReplySample reply;
  reply.request_id = request_id;
  reply.verb = "clear";
  if (loop_.latest().hardware_in_error) {
    // The hardware left its active state: activate it again off the loop, with the loop's
    // calls to it paused at a cycle boundary (granted once the robot stands still).
    // Short: the main thread also keeps systemd's watchdog (2 s) fed.
    constexpr double kPauseTimeoutS = 1.0;
    if (!loop_.pause_hardware(kPauseTimeoutS)) {
      reply.text =
          "refused: hardware_error: the hardware could not be paused for re-activation "
          "(the robot has not come to rest: its last setpoints were not zero); try again";
      return reply;
    }
    const std::string refusal = activate_hardware(hardware_);
    loop_.resume_hardware();
    if (!refusal.empty()) {
      reply.text =
          "refused: hardware plugin '" + hardware_plugin_ + "' refused to re-activate: " + refusal;
      return reply;
    }
    spdlog::info("hardware {} re-activated", hardware_plugin_);
  }
  const std::uint64_t id = ++next_id_;
  loop_.request_clear(id);
  rt::LoopReply answer;
  if (!wait_for_reply(id, answer)) {
    reply.text = "refused: the real-time loop did not answer within 1 s";
    return reply;
  }
  const std::string fault = fault_code_name(answer.fault);
  const std::string cause = answer.detail.data();
  reply.ok = answer.ok;
  if (answer.ok) {
    reply.text = answer.fault == FaultCode::kNone ? "nothing to clear"
                                                  : "cleared " + fault + " (" + cause + ")";
  } else if (answer.fault == FaultCode::kCommandTimeout) {
    reply.text = "refused: " + fault + " persists (" + cause +
                 "): no fresh velocity command; the next one resumes by itself";
  } else {
    reply.text = "refused: " + fault + " persists (" + cause + ")";
  }
  return reply;
}

dds::ReplySample LoopRequests::set_pose(const dds::SetPoseSample& request, bool stopping) {
  dds::ReplySample reply;
  reply.request_id = request.request_id;
  reply.verb = "set_pose";
  const PoseEstimate& p = request.pose;
  const auto& c = p.covariance;
  if (stopping) {
    reply.text = "refused: swiveld is stopping";
  } else if (!finite_pose(p)) {
    reply.text = "refused: the pose (x_m, y_m, yaw_rad) and its covariance must be finite";
  } else if (p.has_covariance && (c[0] < 0.0 || c[4] < 0.0 || c[8] < 0.0)) {
    reply.text = "refused: negative variance (x " + std::to_string(c[0]) + " m^2, y " +
                 std::to_string(c[4]) + " m^2, yaw " + std::to_string(c[8]) + " rad^2)";
  } else {
    const std::uint64_t id = ++next_id_;
    loop_.request_set_pose(p, id);
    rt::LoopReply answer;
    const std::string plugin = loop_.latest().localization_plugin.data();
    if (!wait_for_reply(id, answer)) {
      reply.text = "refused: the real-time loop did not answer within 1 s";
    } else if (!answer.ok) {
      reply.text = "refused by localization '" + plugin + "': " + answer.detail.data();
    } else {
      reply.ok = true;
      reply.text = format("pose set to x=%.3f m y=%.3f m yaw=%.3f rad", p.pose.x_m, p.pose.y_m,
                          p.pose.yaw_rad) +
                   (p.has_covariance ? format(", sigma x=%.3g m y=%.3g m yaw=%.3g rad",
                                              std::sqrt(c[0]), std::sqrt(c[4]), std::sqrt(c[8]))
                                     : std::string(", uncertainty kept")) +
                   " (localization " + plugin + ")";
    }
  }
  if (reply.ok) {
    spdlog::info("set pose from {}: {}", request.source, reply.text);
  } else {
    spdlog::warn("set pose from {}: {}", request.source, reply.text);
  }
  return reply;
}

}  // namespace swivel::daemon
