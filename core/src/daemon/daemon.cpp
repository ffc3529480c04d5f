#include "swivel/daemon/daemon.hpp"

#include <spdlog/spdlog.h>
#include <time.h>

#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <set>

#include "swivel/config/config_error.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {
namespace {

std::vector<std::string> search_path(const DaemonConfig& config) {
  std::vector<std::string> path = config.plugin_path;
  for (auto& dir : PluginLoader::default_search_path()) path.push_back(std::move(dir));
  return path;
}

template <class Interface>
PluginInstance<Interface> create_plugin(PluginLoader& loader, const PluginConfig& slot) {
  try {
    return loader.create<Interface>(slot.plugin);
  } catch (const PluginError& e) {
    throw PluginError(slot.where + " " + e.what());
  }
}

template <class Interface>
void configure_plugin(Interface& plugin, const PluginConfig& slot, const DaemonConfig& config) {
  PluginContext ctx;
  ctx.params = slot.params;
  ctx.config_file = config.file;
  ctx.params_path = slot.params_path;
  ctx.config_dir = config.config_dir;
  ctx.robot = &config.robot;
  ctx.period_s = config.period_s();
  try {
    plugin.configure(ctx);
  } catch (const ConfigError& e) {
    // A copy made here, not a rethrow: the exception object belongs to the plugin's library,
    // which may be unloaded while the stack unwinds (its instance is destroyed on the way).
    throw ConfigError(e.what());
  } catch (const std::exception& e) {
    throw PluginError(slot.where + " plugin '" + slot.plugin + "' failed to configure: " +
                      e.what());
  }
}

const char* mode_name(LoopMode mode) {
  switch (mode) {
    case LoopMode::kIdle: return "idle";
    case LoopMode::kVelocity: return "velocity";
    case LoopMode::kCalibration: return "calibration";
    case LoopMode::kSafeStop: return "safe_stop";
  }
  return "unknown";
}

timespec to_timespec(double seconds) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(seconds);
  ts.tv_nsec = static_cast<long>((seconds - static_cast<double>(ts.tv_sec)) * 1e9);
  return ts;
}

}  // namespace

double monotonic_now_s() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

Daemon::Daemon(DaemonConfig config) : config_(std::move(config)), loader_(search_path(config_)) {
  hardware_ = create_plugin<Hardware>(loader_, config_.hardware);
  drivetrain_ = create_plugin<Drivetrain>(loader_, config_.drivetrain);
  localization_ = create_plugin<Localization>(loader_, config_.localization);
  configure_plugin(*hardware_, config_.hardware, config_);
  configure_plugin(*drivetrain_, config_.drivetrain, config_);
  configure_plugin(*localization_, config_.localization, config_);
  if (drivetrain_->module_count() != config_.robot.module_count()) {
    throw PluginError(config_.drivetrain.where + " plugin '" + config_.drivetrain.plugin +
                      "' drives " + std::to_string(drivetrain_->module_count()) +
                      " modules, but robot model " + config_.robot_model_path + " has " +
                      std::to_string(config_.robot.module_count()));
  }
  localization_->reset(PoseEstimate{});
}

Daemon::~Daemon() { stop(); }

void Daemon::start() {
  rt::LoopOptions options;
  options.rate_hz = config_.rate_hz;
  options.fifo_priority = config_.fifo_priority;
  options.realtime = config_.realtime;
  options.command_timeout_s = config_.command.timeout_s;
  loop_ = std::make_unique<rt::ControlLoop>(options, *hardware_, *drivetrain_, *localization_,
                                            config_.localization.plugin.c_str());
  start_s_ = monotonic_now_s();
  std::set<std::string> seen;
  for (const auto& warning : loop_->start()) {
    if (seen.insert(warning).second) spdlog::warn("{}", warning);
  }
  spdlog::info("loop running at {} Hz: hardware {}, drivetrain {}, localization {}, robot {}",
               config_.rate_hz, config_.hardware.plugin, config_.drivetrain.plugin,
               config_.localization.plugin, config_.robot.name);
  if (config_.command.source == CommandSource::kScript) {
    command_thread_ = std::jthread([this](const std::stop_token& stop) { run_script(stop); });
    spdlog::info("command source: script of {} steps, played in a loop",
                 config_.command.script.size());
  }
}

void Daemon::stop() noexcept {
  if (command_thread_.joinable()) {
    command_thread_.request_stop();
    command_thread_.join();
  }
  if (loop_) {
    loop_->stop();
    loop_.reset();
  }
}

void Daemon::run_script(const std::stop_token& stop) {
  constexpr double kPushPeriodS = 0.02;  // 50 Hz: well inside any sensible command timeout
  const auto& script = config_.command.script;
  double total_s = 0.0;
  for (const auto& step : script) total_s += step.duration_s;
  std::mutex mutex;
  std::condition_variable_any wake;
  std::uint64_t sequence = 0;
  std::unique_lock lock(mutex);
  while (!stop.stop_requested()) {
    const double now = monotonic_now_s();
    double into_s = std::fmod(now - start_s_, total_s);
    std::size_t i = 0;
    while (i + 1 < script.size() && into_s >= script[i].duration_s) {
      into_s -= script[i].duration_s;
      ++i;
    }
    VelocityCommand command;
    command.twist = script[i].twist;
    command.received_s = now;
    command.sequence = ++sequence;
    loop_->push_command(command);
    wake.wait_for(lock, stop, std::chrono::duration<double>(kPushPeriodS), [] { return false; });
  }
}

int Daemon::run_until_signal(const sigset_t& signals) {
  double next_s = monotonic_now_s() + config_.status_period_s;
  for (;;) {
    const double wait_s = std::max(0.0, next_s - monotonic_now_s());
    const timespec timeout = to_timespec(wait_s);
    const int signal = sigtimedwait(&signals, nullptr, &timeout);
    if (signal > 0) return signal;
    if (errno == EAGAIN) {
      std::fputs((status_line() + "\n").c_str(), stdout);
      std::fflush(stdout);
      next_s += config_.status_period_s;
    }
  }
}

std::string Daemon::status_line() const {
  if (!loop_) return "not running";
  const StateSnapshot s = loop_->latest();
  const auto timing = loop_->timing();
  char line[512];
  int n = std::snprintf(line, sizeof line, "t=%.2fs pose x=%.3f m y=%.3f m yaw=%.3f rad",
                        s.stamp_s - start_s_, s.estimate.pose.x_m, s.estimate.pose.y_m,
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
