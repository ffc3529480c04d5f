// SPDX-License-Identifier: Apache-2.0
#include "service_integration.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <utility>

#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {
namespace {

const char* mode_name(LoopMode mode) {
  switch (mode) {
    case LoopMode::kIdle: return "idle";
    case LoopMode::kVelocity: return "velocity";
    case LoopMode::kCalibration: return "calibration";
    case LoopMode::kSafeStop: return "safe_stop";
  }
  return "unknown";
}

}  // namespace

ServiceIntegration::ServiceIntegration(service::Notifier notifier)
    : notifier_(std::move(notifier)) {}

void ServiceIntegration::ready(const std::string& status) {
  // Unsent, systemd would time the start out: say why it may.
  if (notifier_.enabled() && !notifier_.ready(status)) {
    spdlog::warn("sd_notify: READY=1 could not be sent to {}", notifier_.socket_path());
  }
}

void ServiceIntegration::reloading(const std::string& status) {
  if (notifier_.enabled() && !notifier_.reloading(status)) {
    spdlog::warn("sd_notify: RELOADING=1 could not be sent to {}", notifier_.socket_path());
  }
}

void ServiceIntegration::stopping() noexcept {
  if (!notifier_.enabled()) return;
  try {
    (void)notifier_.stopping();  // on the way out: nobody to tell if it fails
  } catch (...) {
  }
}

void ServiceIntegration::start_watchdog(double now_s) {
  watchdog_interval_ = service::watchdog_interval_from_environment();
  watchdog_period_s_ =
      watchdog_interval_ ? static_cast<double>(watchdog_interval_->count()) * 1e-6 / 2.0 : 0.0;
  next_watchdog_s_ = now_s;
}

std::optional<double> ServiceIntegration::next_watchdog_s() const {
  if (!watchdog_interval_) return std::nullopt;
  return next_watchdog_s_;
}

void ServiceIntegration::tick_watchdog(const rt::ControlLoop* loop, double now_s) {
  if (!watchdog_interval_ || now_s < next_watchdog_s_) return;
  next_watchdog_s_ = now_s + watchdog_period_s_;
  if (loop == nullptr || !notifier_.enabled()) return;
  // Healthy means the loop has run cycles since the last ping.
  const std::uint64_t cycle = loop->latest().cycle;
  // A lost ping is a missed ping: systemd acts on the next one missing too.
  if (cycle > watchdog_cycle_ && loop->running()) (void)notifier_.watchdog();
  watchdog_cycle_ = cycle;
}

std::string format_status_line(const StateSnapshot& s, const rt::TimingReport& timing,
                               double start_s) {
  char line[512];
  int n = std::snprintf(line, sizeof line, "t=%.2fs pose x=%.3f m y=%.3f m yaw=%.3f rad",
                        s.stamp_s - start_s, s.estimate.pose.x_m, s.estimate.pose.y_m,
                        s.estimate.pose.yaw_rad);
  std::string text(line, static_cast<std::size_t>(n));
  if (s.has_truth) {
    n = std::snprintf(line, sizeof line, " | truth x=%.3f m y=%.3f m yaw=%.3f rad", s.truth.x_m,
                      s.truth.y_m, s.truth.yaw_rad);
    text.append(line, static_cast<std::size_t>(n));
  }
  n = std::snprintf(line, sizeof line,
                    " | cmd vx=%.2f vy=%.2f wz=%.2f | mode %s fault %s | loop p99.9 late %.0fus "
                    "overruns %llu",
                    s.command_twist.vx_mps, s.command_twist.vy_mps, s.command_twist.wz_radps,
                    mode_name(s.mode), fault_code_name(s.fault), timing.lateness_p999_us,
                    static_cast<unsigned long long>(timing.overruns));
  text.append(line, static_cast<std::size_t>(n));
  return text;
}

}  // namespace swivel::daemon
