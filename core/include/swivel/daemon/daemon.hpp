#pragma once
// The daemon's wiring: plugins from the configuration, the real-time loop, the command
// source and the status output. main() only parses the command line and handles signals;
// the DDS bridge and configuration reload hook in here.

#include <signal.h>

#include <memory>
#include <string>
#include <thread>

#include "swivel/daemon/daemon_config.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/plugin_loader.hpp"

namespace swivel::rt {
class ControlLoop;
}

namespace swivel::daemon {

/// Monotonic time in seconds (CLOCK_MONOTONIC, the loop's clock).
double monotonic_now_s() noexcept;

class Daemon {
 public:
  /// Loads every plugin and configures it, and resets the localization at the origin.
  /// Nothing runs yet, so a failure here leaves no thread behind.
  /// @throws ConfigError (a plugin's params) or PluginError (loading), both naming the
  ///         configuration file, line and key.
  explicit Daemon(DaemonConfig config);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  /// Starts the real-time loop and the command source. Logs each real-time warning
  /// (scheduling, memory locking) once.
  void start();

  /// Stops the command source, then the loop (which leaves the robot at zero velocity).
  /// Idempotent.
  void stop() noexcept;

  /// Prints a status line every status period until one of `signals` arrives (they must be
  /// blocked in every thread). Returns the signal number.
  int run_until_signal(const sigset_t& signals);

  /// One status line: estimated and true pose, command, mode, fault and loop timing.
  [[nodiscard]] std::string status_line() const;

  [[nodiscard]] const DaemonConfig& config() const { return config_; }
  [[nodiscard]] PluginLoader& loader() { return loader_; }
  /// The loop, once started (null before start() and after stop()).
  [[nodiscard]] rt::ControlLoop* loop() { return loop_.get(); }

 private:
  void run_script(const std::stop_token& stop);

  DaemonConfig config_;
  PluginLoader loader_;
  PluginInstance<Hardware> hardware_;
  PluginInstance<Drivetrain> drivetrain_;
  PluginInstance<Localization> localization_;
  std::unique_ptr<rt::ControlLoop> loop_;
  std::jthread command_thread_;
  double start_s_ = 0.0;
};

}  // namespace swivel::daemon
