// SPDX-License-Identifier: Apache-2.0
#include "diagnostics.hpp"

#include <utility>

#include "swivel/clock.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {

void ReloadRecord::record(const ReloadResult& result) {
  const std::lock_guard lock(mutex_);
  ++summary_.count;
  summary_.last = result;
  if (result.ok) summary_.restart_required = result.restart_required;
}

void ReloadRecord::set_robot_model(const std::string& path) {
  const std::lock_guard lock(mutex_);
  summary_.robot_model = path;
}

ReloadRecord::Summary ReloadRecord::summary() const {
  const std::lock_guard lock(mutex_);
  return summary_;
}

DiagnosticsSource::DiagnosticsSource(const rt::ControlLoop& loop, std::string hardware_plugin,
                                     std::string drivetrain_plugin, double start_s,
                                     const ReloadRecord& reloads)
    : loop_(loop),
      hardware_plugin_(std::move(hardware_plugin)),
      drivetrain_plugin_(std::move(drivetrain_plugin)),
      start_s_(start_s),
      reloads_(reloads) {}

dds::DiagnosticsSample DiagnosticsSource::read() {
  dds::DiagnosticsSample d;
  const auto timing = loop_.timing();
  const StateSnapshot s = loop_.latest();
  const double now = monotonic_s();
  d.uptime_s = now - start_s_;
  d.loop_rate_hz = 1.0 / loop_.period_s();
  if (rate_window_s_ > 0.0 && now > rate_window_s_) {
    measured_rate_hz_ = static_cast<double>(s.cycle - rate_window_cycles_) / (now - rate_window_s_);
  }
  rate_window_s_ = now;
  rate_window_cycles_ = s.cycle;
  d.measured_rate_hz = measured_rate_hz_;
  d.lateness = {timing.lateness_p50_us, timing.lateness_p99_us, timing.lateness_p999_us,
                timing.lateness_max_us};
  d.cycle_time = {timing.cycle_p50_us, timing.cycle_p99_us, timing.cycle_p999_us,
                  timing.cycle_max_us};
  d.cycles = timing.cycles;
  d.overruns = timing.overruns;
  d.fault_count = s.fault_count;
  d.mode = s.mode;
  d.fault = s.fault;
  d.fault_detail = s.fault_detail.data();
  d.hardware_plugin = hardware_plugin_;
  d.drivetrain_plugin = drivetrain_plugin_;
  d.localization_plugin = s.localization_plugin.data();
  const ReloadRecord::Summary reloads = reloads_.summary();
  d.robot_model = reloads.robot_model;
  d.reload_count = reloads.count;
  d.last_reload_ok = reloads.last.ok;
  d.last_reload_result = reloads.last.text;
  d.restart_required = reloads.restart_required;
  return d;
}

}  // namespace swivel::daemon
