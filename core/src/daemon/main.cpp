// SPDX-License-Identifier: Apache-2.0
// swiveld: runs a robot from the real-time loop with the plugins its configuration names.
//   swiveld --config FILE [--check] [--log-level LEVEL] [--record LOG.csv [--record-rate-hz HZ]]
// SIGTERM/SIGINT stop it, SIGHUP reloads the configuration.

#include <malloc.h>
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "swivel/cli/command_line.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/daemon/daemon.hpp"
#include "swivel/daemon/daemon_config.hpp"
#include "swivel/plugin_loader.hpp"

namespace {

// glibc's threshold for giving a block its own mapping: its default, made fixed.
constexpr int kOwnMappingFromBytes = 128 * 1024;

int run(int argc, char** argv) {
  // Blocks this large (Cyclone DDS's 1 MiB receive buffers, replaced as they fill) always get
  // a mapping of their own, returned when freed. By default glibc raises the threshold once
  // such a block is freed, and the next ones come from a thread's arena, whose pages then stay
  // resident (all of them under mlockall): a step of 1.1 MiB within 1,000 reloads.
  mallopt(M_MMAP_THRESHOLD, kOwnMappingFromBytes);
  CLI::App app{"swiveld: the Swivel robot control daemon"};
  std::string config_file;
  bool check = false;
  std::string log_level;
  app.add_option("-c,--config", config_file, "configuration file (YAML)")->required();
  app.add_flag("--check", check, "validate the configuration and plugins, then exit");
  app.add_option("--log-level", log_level, "overrides logging.level")
      ->check(CLI::IsMember(swivel::daemon::log_level_names()));
  swivel::daemon::DaemonOptions options;
  app.add_option("--record", options.record_path,
                 "record the run as a run log (CSV, the format of swivel-lab)");
  app.add_option("--record-rate-hz", options.record_rate_hz, "run-log rows per second")
      ->check(CLI::Range(0.1, 10000.0))
      ->capture_default_str();
  app.add_flag("!--no-dds", options.dds, "do not start the DDS bridge");
  if (const auto exit = swivel::cli::parse(app, argc, argv, "swiveld")) return *exit;

  // Block the stop and reload signals before any thread exists so that every thread inherits the
  // mask and only run_until_signal() receives them (no work in a signal handler).
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGTERM);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  auto logger = spdlog::stderr_color_mt("swiveld");
  logger->set_pattern("%Y-%m-%d %H:%M:%S.%e swiveld %^%l%$: %v");
  spdlog::set_default_logger(logger);

  try {
    swivel::daemon::DaemonConfig config = swivel::daemon::load_daemon_config(config_file);
    spdlog::set_level(spdlog::level::from_str(log_level.empty() ? config.log_level : log_level));
    swivel::daemon::Daemon daemon(std::move(config), options);
    const auto& c = daemon.config();
    if (check) {
      std::printf(
          "%s: configuration valid (robot %s, hardware %s, drivetrain %s, "
          "localization %s)\n",
          c.file.c_str(), c.robot.name.c_str(), c.hardware.plugin.c_str(),
          c.drivetrain.plugin.c_str(), c.localization.plugin.c_str());
      return 0;
    }
    daemon.start();
    const int signal = daemon.run_until_signal(stop_signals);
    spdlog::info("received {}, stopping", signal == SIGINT ? "SIGINT" : "SIGTERM");
    daemon.stop();
    std::fflush(stdout);
    if (!options.record_path.empty()) spdlog::info("run log written to {}", options.record_path);
    if (!daemon.hardware_stopped()) {
      // The loop's last setpoints were zero, but the drives did not confirm they are off.
      spdlog::error("stopped, but the drives were not confirmed off (see above)");
      return 1;
    }
    spdlog::info("stopped cleanly: robot at zero velocity");
    return 0;
  } catch (const swivel::ConfigError& e) {
    spdlog::error("{}", e.what());
  } catch (const swivel::PluginError& e) {
    spdlog::error("{}", e.what());
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
  }
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  // What escapes run() (argument parsing, the logger's set-up) still ends with a message.
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swiveld: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "swiveld: unknown exception\n");
  }
  return 1;
}
