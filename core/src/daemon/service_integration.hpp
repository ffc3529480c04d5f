// SPDX-License-Identifier: Apache-2.0
#pragma once
// Running as a systemd service (Type=notify, WatchdogSec=): READY=1, RELOADING=1 and
// STOPPING=1 around the daemon's life and reloads, WATCHDOG=1 only while the real-time loop's
// cycle count advances (a stalled loop lets the watchdog fire), and the one-line status the
// daemon prints on stdout. Outside systemd (no NOTIFY_SOCKET) the notifications do nothing.
//
// Main thread only. Not real-time safe.

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "swivel/rt/state_snapshot.hpp"
#include "swivel/rt/timing_stats.hpp"
#include "swivel/service/sd_notify.hpp"

namespace swivel::rt {
class ControlLoop;
}

namespace swivel::daemon {

class ServiceIntegration {
 public:
  /// Notifies through `notifier` (by default NOTIFY_SOCKET's).
  explicit ServiceIntegration(service::Notifier notifier = service::Notifier::from_environment());

  void ready(const std::string& status);
  void reloading(const std::string& status);
  void stopping() noexcept;

  /// Reads WATCHDOG_USEC (and WATCHDOG_PID); from then on tick_watchdog() pings at half the
  /// interval. `now_s` (monotonic) is when the first ping is due.
  void start_watchdog(double now_s);

  /// Sends WATCHDOG=1 when a ping is due and `loop` runs and has completed cycles since the
  /// last ping. Does nothing without a watchdog or a loop.
  void tick_watchdog(const rt::ControlLoop* loop, double now_s);

  /// When the next ping is due (monotonic seconds); std::nullopt without a watchdog.
  [[nodiscard]] std::optional<double> next_watchdog_s() const;

 private:
  service::Notifier notifier_;
  std::optional<std::chrono::microseconds> watchdog_interval_;
  double watchdog_period_s_ = 0.0;
  double next_watchdog_s_ = 0.0;
  std::uint64_t watchdog_cycle_ = 0;
};

/// The status line: estimated and true pose, command, mode, fault and loop timing, e.g.
/// "t=3.00s pose x=0.900 m y=0.000 m yaw=0.000 rad | truth ... | cmd vx=0.30 vy=0.00 wz=0.00 |
/// mode velocity fault none | loop p99.9 late 45us overruns 0". `start_s` is the loop's
/// start on the snapshot's clock.
std::string format_status_line(const StateSnapshot& s, const rt::TimingReport& timing,
                               double start_s);

}  // namespace swivel::daemon
