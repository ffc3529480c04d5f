// SPDX-License-Identifier: Apache-2.0
#pragma once
// The daemon's side of a calibration (docs/architecture.md "Plugin kinds", calibration kind):
// creates and configures the calibration plugin, hands it to the real-time loop, follows its
// progress, takes it back when the loop lets go of it, analyses the recording on a worker thread,
// writes the calibrated robot model as a new file (calibration_output.hpp: the
// service's state directory, else next to the nominal one) and reports
// everything as CalibrationResult samples through a callback.
//
// Nothing here runs on the loop thread. Every public method may be called from any
// non-real-time thread (a mutex serialises them); the daemon calls poll() periodically.
// The runner must be destroyed while the loop still runs or after it stopped; the
// destructor cancels a running procedure and waits (at most a few seconds) for the loop to
// hand the instance back before destroying it.

#include <ctime>
#include <functional>
#include <future>
#include <mutex>
#include <optional>
#include <string>

#include "swivel/dds/bridge.hpp"
#include "swivel/plugin/calibration.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/plugin_loader.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {

class CalibrationRunner {
 public:
  /// Receives every sample to publish (status changes and progress). Called on the thread
  /// that called the runner's method, with the runner's mutex held: do not call back.
  using Publish = std::function<void(const dds::CalibrationSample&)>;

  /// Not real-time safe. `nominal` and `context` are copied; `context.robot` is replaced by
  /// the copy of `nominal`. `model_path` is the nominal model's file (the calibrated one is
  /// written where calibration_output_dirs() says).
  CalibrationRunner(rt::ControlLoop& loop, PluginLoader& loader, RobotModel nominal,
                    std::string model_path, PluginContext context,
                    std::string plugin = "swpc_geometric", Publish publish = {});
  ~CalibrationRunner();
  CalibrationRunner(const CalibrationRunner&) = delete;
  CalibrationRunner& operator=(const CalibrationRunner&) = delete;

  /// Creates and configures a fresh plugin instance and hands it to the loop. Returns ""
  /// when started, else why not (already running, analysing, plugin or configuration
  /// error); publishes the resulting status either way.
  std::string start();

  /// Stops a running procedure (the loop writes zero setpoints at its next cycle). The
  /// status becomes "cancelled" once the loop has handed the instance back (poll()).
  void cancel();

  /// The current status: idle | running | done | failed | cancelled, with progress, a
  /// text, and the calibrated modules with their uncertainties once done.
  [[nodiscard]] dds::CalibrationSample status() const;

  /// Periodic work: publishes progress at most every `progress_period_s`, takes the
  /// instance back when the loop lets go, starts the analysis and, when it is ready, writes
  /// the calibrated model and publishes the result.
  void poll();

  /// Handles a Request: argument "start" | "cancel" | "status". Publishes the status.
  void handle_request(const std::string& argument);

  /// Where the last calibrated model was written ("" when none).
  [[nodiscard]] std::string calibrated_model_file() const;

  /// The calibrated model applies with `robot_model:` set to calibrated_model_file() and a
  /// reload with the robot at rest. Returns that instruction, or why there is nothing to
  /// apply.
  [[nodiscard]] std::string apply_instructions() const;

  /// Seconds between progress samples published by poll().
  void set_progress_period(double seconds) { progress_period_s_ = seconds; }

 private:
  void publish_locked();
  void finish_analysis_locked();
  void fill_modules_locked(const CalibrationReport& report);
  void set_status_locked(const std::string& status, const std::string& text);

  rt::ControlLoop& loop_;
  PluginLoader& loader_;
  RobotModel nominal_;
  std::string model_path_;
  PluginContext context_;
  std::string plugin_name_;
  Publish publish_;

  mutable std::mutex mutex_;
  PluginInstance<Calibration> instance_;  // configured, in the loop, or being analysed
  std::optional<std::future<CalibrationReport>> analysis_;
  dds::CalibrationSample status_;
  std::string calibrated_file_;
  double progress_period_s_ = 0.5;
  double last_progress_s_ = -1e9;
};

}  // namespace swivel::daemon
