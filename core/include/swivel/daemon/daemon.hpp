// SPDX-License-Identifier: Apache-2.0
#pragma once
// The daemon's wiring: plugins from the configuration, the real-time loop, the command
// source, the DDS bridge, the systemd notifications, configuration reload (file watcher,
// SIGHUP, DDS `reload` request), the run-log recorder and the status output. main() only
// parses the command line and blocks the signals.
//
// Threads: the main thread (run_until_signal) owns reloads, hot swaps, requests, the
// watchdog and the calibration's periodic work; the loop thread runs the plugins; the
// bridge has a publisher and a subscriber thread (which queues requests for the main
// thread); the run-sample publisher (swivel_run_samples, fed by the loop's run-sample
// ring), the script command source, the recorder and the file watcher have one thread each.
// Nothing added here runs on the loop thread.
//
// Requests (DDS Request and SetPose, ROS 2 initialpose) are answered one at a time by the
// main thread, each with a Reply carrying its request id:
//  - reload: the result of re-reading the configuration;
//  - clear: the active fault is left when its cause is gone, refused with the cause while
//    it persists; a hardware in its error state is re-activated first (its calls paused at
//    a cycle boundary, Hardware::activate() off the loop);
//  - set_pose: the estimate set through the active localization's hand-over;
//  - calibrate: start | cancel | status of the CalibrationRunner, which hands the plugin to
//    the loop (mode kCalibration: velocity commands and the script are ignored meanwhile),
//    analyses the recording off the loop and writes the calibrated model next to the nominal
//    one. Progress and results go out as CalibrationResult samples; without a calibration
//    section every calibrate request is refused with the reason.
//
// Each of these jobs is a type of its own in core/src/daemon/, which this class wires
// together: plugin_set (creating and configuring plugins, at start-up and on reload),
// reload_plan (what a new configuration changes: a pure function), hot_swap (a new
// localization or robot model under the running loop), request_router (the DDS request queue and
// its verbs), loop_requests (clear and set-pose through the loop), calibration_service (calibrate
// and the runner's polling), script_source (the built-in command source), run_recorder (--record),
// diagnostics (the Diagnostics sample), service_integration (sd_notify, watchdog, status line),
// controlled_stop and hardware_lifecycle (shutdown).
//
// Hardware lifecycle (swivel/plugin/hardware.hpp): configure() in the constructor,
// activate() in start() before the loop's first cycle, deactivate() in stop() after its
// last. On SIGTERM/SIGINT stop() stops the robot first: no more commands, a controlled stop
// to rest while the loop runs, the loop's final cycle, deactivate(), and only then the
// watcher, the DDS bridge and the calibration runner.

#include <signal.h>

#include <atomic>
#include <memory>
#include <string>

#include "swivel/daemon/daemon_config.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/options.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/plugin_loader.hpp"

namespace swivel::rt {
class ControlLoop;
}
namespace swivel::dds {
class RunSamplePublisher;
}

namespace swivel::daemon {

class CalibrationService;
class ConfigWatcher;
class DiagnosticsSource;
class HotSwap;
class LoopRequests;
class ReloadRecord;
class RequestQueue;
class RunRecorder;
class ScriptCommandSource;
class ServiceIntegration;
struct RequestHandlers;

/// What the command line adds to the configuration file.
struct DaemonOptions {
  std::string record_path;        ///< run log (CSV) to record; "" records nothing
  double record_rate_hz = 100.0;  ///< rows per second in the run log
  bool dds = true;                ///< start the DDS bridge
  bool watch_config = true;       ///< reload when the configuration file changes
};

/// The outcome of one configuration reload.
struct ReloadResult {
  bool ok = false;
  bool restart_required = false;  ///< some changed settings wait for a restart
  std::string text;               ///< what was applied, what needs a restart, or the error
};

class Daemon {
 public:
  /// Loads every plugin and configures it (the calibration plugin once, to validate its
  /// params), resets the localization at the origin and validates the `dds:` section.
  /// Nothing runs yet, so a failure here leaves no thread.
  /// @throws ConfigError (a plugin's params, dds) or PluginError (loading), both naming the
  ///         configuration file, line and key.
  explicit Daemon(DaemonConfig config, DaemonOptions options = {});
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  /// Starts the recorder's file, activates the hardware, starts the real-time loop, the
  /// calibration runner (when configured), the command source, the DDS bridge and the
  /// configuration watcher, then notifies READY=1. Logs each real-time warning once.
  /// @throws RunLogError when the run log cannot be created; DdsError when DDS refuses;
  ///         PluginError naming the plugin and its reason when the hardware refuses to
  ///         activate.
  void start();

  /// Stops the robot first, then everything else. Notifies STOPPING=1, stops accepting
  /// commands and requests (the script stops, DDS commands are dropped), brings the robot to
  /// rest within the controlled stop's limits while the loop still runs, stops the loop
  /// (its final cycle writes zero setpoints), deactivates the hardware, and only then stops
  /// the watcher, the bridge, the calibration runner and the recorder. Idempotent.
  void stop() noexcept;

  /// After stop(): false when the hardware's deactivate() failed (the drives were not
  /// confirmed off; its message was logged).
  [[nodiscard]] bool hardware_stopped() const noexcept { return hardware_stopped_; }

  /// Prints a status line every status period, sends the watchdog while the loop advances
  /// and performs reloads (SIGHUP, file change, DDS request) until SIGTERM or SIGINT
  /// arrives. `signals` must hold SIGTERM, SIGINT and SIGHUP, blocked in every thread.
  /// Returns the stopping signal's number.
  int run_until_signal(const sigset_t& signals);

  /// Re-reads and validates the configuration file and applies what can change live (the
  /// localization by hot swap; a new robot model by swapping in a drivetrain and a
  /// localization built for it, with the robot at rest; logging level, status period; a
  /// changed `calibration:` needs a restart). Main thread only, while the loop runs.
  /// `trigger` names the cause in the log.
  ReloadResult reload(const std::string& trigger);

  /// Asks the main thread to reload soon (any thread).
  void request_reload() noexcept { reload_requested_.store(true, std::memory_order_release); }

  /// One status line: estimated and true pose, command, mode, fault and loop timing.
  [[nodiscard]] std::string status_line() const;

  [[nodiscard]] const DaemonConfig& config() const { return config_; }
  [[nodiscard]] PluginLoader& loader() { return loader_; }
  /// The loop, once started (null before start() and after stop()).
  [[nodiscard]] rt::ControlLoop* loop() { return loop_.get(); }

  /// Answers one request: verb "reload", "clear" or "calibrate" (argument start | cancel |
  /// status). Main thread only (the one that runs reloads), while the loop runs. A
  /// calibrate request also publishes the calibration's status as a CalibrationResult.
  dds::ReplySample handle_request(const dds::RequestSample& request);

  /// Sets the pose estimate through the active localization's hand-over at a cycle
  /// boundary; refused (nothing changes) for a non-finite pose or covariance, a negative
  /// variance, or when the plugin refuses. Main thread only, while the loop runs.
  dds::ReplySample set_pose(const dds::SetPoseSample& request);

 private:
  void start_bridge();
  void publish_calibration(const dds::CalibrationSample& sample) noexcept;
  void publish_reply(const dds::ReplySample& reply);
  void apply_robot_model(const DaemonConfig& fresh, std::string text);

  // Declared in the order they must outlive one another (stop() tears down explicitly, in
  // the order it documents): the loop uses the plugins, the threads around it use the loop,
  // the DDS bridge's callbacks use the request queue and the reload record.
  DaemonConfig config_;  // the configuration in effect (main thread writes, on reload)
  DaemonOptions options_;
  dds::DdsOptions dds_options_;
  std::string robot_model_text_;  // the model in effect, to tell a changed one apart on reload
  std::unique_ptr<ServiceIntegration> service_;
  std::unique_ptr<ReloadRecord> reloads_;
  std::unique_ptr<RequestQueue> requests_;     // subscriber thread -> main thread
  std::unique_ptr<RequestHandlers> handlers_;  // who answers each verb (main thread)
  PluginLoader loader_;
  PluginInstance<Hardware> hardware_;
  std::unique_ptr<HotSwap> hot_swap_;  // the loop's drivetrain and localization, a swap in flight
  std::unique_ptr<RunRecorder> recorder_;
  std::unique_ptr<rt::ControlLoop> loop_;
  std::unique_ptr<LoopRequests> loop_requests_;
  std::unique_ptr<DiagnosticsSource> diagnostics_;  // publisher thread
  std::unique_ptr<dds::DdsBridge> bridge_;
  std::unique_ptr<dds::RunSamplePublisher> run_samples_;  // on the bridge's participant
  std::unique_ptr<CalibrationService> calibration_;
  std::unique_ptr<ConfigWatcher> watcher_;
  std::unique_ptr<ScriptCommandSource> script_;
  double start_s_ = 0.0;
  double status_period_s_ = 1.0;
  std::atomic<bool> reload_requested_{false};
  std::atomic<bool> stopping_{false};  // stop() began: no more commands or requests
  bool hardware_active_ = false;       // activate() succeeded, deactivate() not yet called
  bool hardware_stopped_ = true;       // no deactivate() failed
};

}  // namespace swivel::daemon
