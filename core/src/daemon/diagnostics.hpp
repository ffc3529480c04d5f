// SPDX-License-Identifier: Apache-2.0
#pragma once
// The daemon's Diagnostics sample (published by the DDS bridge's publisher thread): loop
// rates and timing percentiles, faults, the plugins and the robot model in use and the
// outcome of the last configuration reload.

#include <cstdint>
#include <mutex>
#include <string>

#include "swivel/daemon/daemon.hpp"
#include "swivel/dds/bridge.hpp"

namespace swivel::rt {
class ControlLoop;
}

namespace swivel::daemon {

/// The reloads so far and the robot model they left in effect: written by the main thread,
/// read by the publisher thread.
class ReloadRecord {
 public:
  struct Summary {
    std::uint32_t count = 0;
    ReloadResult last{true, false, ""};
    bool restart_required = false;  ///< as of the last reload that was accepted
    std::string robot_model;        ///< the model file in effect
  };

  void record(const ReloadResult& result);
  /// The model file in effect: at start-up and whenever a reload applied another.
  void set_robot_model(const std::string& path);
  [[nodiscard]] Summary summary() const;

 private:
  mutable std::mutex mutex_;
  Summary summary_;
};

/// Builds Diagnostics samples. Publisher thread only (it keeps the measured-rate window).
class DiagnosticsSource {
 public:
  /// `hardware_plugin` and `drivetrain_plugin` never change while running (a new robot
  /// model brings a new instance of the same drivetrain plugin); the localization's name is
  /// the loop's, the robot model the reload record's. `start_s` is when the loop started
  /// (monotonic).
  DiagnosticsSource(const rt::ControlLoop& loop, std::string hardware_plugin,
                    std::string drivetrain_plugin, double start_s, const ReloadRecord& reloads);

  dds::DiagnosticsSample read();

 private:
  const rt::ControlLoop& loop_;
  std::string hardware_plugin_;
  std::string drivetrain_plugin_;
  double start_s_;
  const ReloadRecord& reloads_;
  double rate_window_s_ = 0.0;
  std::uint64_t rate_window_cycles_ = 0;
  double measured_rate_hz_ = 0.0;
};

}  // namespace swivel::daemon
