// SPDX-License-Identifier: Apache-2.0
#include "swivel/daemon/daemon.hpp"

#include <spdlog/spdlog.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "calibration_service.hpp"
#include "config_watcher.hpp"
#include "controlled_stop.hpp"
#include "diagnostics.hpp"
#include "hardware_lifecycle.hpp"
#include "hot_swap.hpp"
#include "loop_requests.hpp"
#include "plugin_set.hpp"
#include "reload_plan.hpp"
#include "reload_swap.hpp"
#include "request_router.hpp"
#include "run_recorder.hpp"
#include "script_source.hpp"
#include "service_integration.hpp"
#include "swivel/clock.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/dds/run_sample_publisher.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// How long a reload waits for the loop to take a swap: a localization's is taken at the next
// cycle; a new robot model's at the first cycle with the robot at rest.
constexpr double kSwapWaitS = 2.0;

timespec to_timespec(double seconds) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(seconds);
  ts.tv_nsec = static_cast<long>((seconds - static_cast<double>(ts.tv_sec)) * 1e9);
  return ts;
}

}  // namespace

Daemon::Daemon(DaemonConfig config, DaemonOptions options)
    : config_(std::move(config)),
      options_(std::move(options)),
      service_(std::make_unique<ServiceIntegration>()),
      reloads_(std::make_unique<ReloadRecord>()),
      requests_(std::make_unique<RequestQueue>()),
      handlers_(std::make_unique<RequestHandlers>()),
      loader_(plugin_search_path(config_)) {
  dds_options_ = dds::parse_dds_options(config_.dds, config_.file, config_.config_dir);
  dds::complete_joints(config_.robot, config_.file, dds_options_.ros2);
  if (dds_options_.run_samples_rate_hz > config_.rate_hz) {
    throw ConfigError(fmt::format(
        "{}: dds.run_samples_rate_hz: expected at most loop.rate_hz ({:g} Hz), got {:g}",
        config_.file, config_.rate_hz, dds_options_.run_samples_rate_hz));
  }
  // A configured sensor without the bridge would only ever be stale.
  if (!options_.dds && (dds_options_.ros2.imu.enabled || dds_options_.ros2.mocap_pose.enabled)) {
    throw ConfigError(config_.file + ": dds.ros2." +
                      (dds_options_.ros2.imu.enabled ? "imu" : "mocap_pose") +
                      ": a ROS 2 sensor topic needs the DDS bridge, but --no-dds was given");
  }
  robot_model_text_ = read_text(config_.robot_model_path);
  status_period_s_ = config_.status_period_s;
  reloads_->set_robot_model(config_.robot_model_path);
  PluginSet plugins = assemble_plugins(loader_, config_);
  hardware_ = std::move(plugins.hardware);
  hot_swap_ = std::make_unique<HotSwap>(std::move(plugins.localization), config_.localization,
                                        std::move(plugins.drivetrain));
  if (!(options_.record_rate_hz > 0.0 && options_.record_rate_hz <= 10000.0)) {
    throw ConfigError("--record-rate-hz: expected a rate in (0, 10000] Hz");
  }
  handlers_->reload = [this] {
    const ReloadResult result = reload("reload request");
    dds::ReplySample reply;
    reply.ok = result.ok;
    reply.text = result.text;
    return reply;
  };
  handlers_->clear = [this](std::uint64_t id) { return loop_requests_->clear(id); };
  handlers_->calibrate = [this](const std::string& argument) {
    return calibration_->handle(argument);
  };
  handlers_->set_pose = [this](const dds::SetPoseSample& pose) { return set_pose(pose); };
}

Daemon::~Daemon() { stop(); }

void Daemon::start() {
  if (!options_.record_path.empty()) {
    recorder_ = std::make_unique<RunRecorder>(options_.record_path, options_.record_rate_hz,
                                              config_.robot, config_.file);
  }

  rt::LoopOptions loop_options;
  loop_options.rate_hz = config_.rate_hz;
  loop_options.fifo_priority = config_.fifo_priority;
  loop_options.realtime = config_.realtime;
  loop_options.command_timeout_s = config_.command.timeout_s;
  loop_options.limits = config_.robot.limits;
  loop_options.stop_linear_deceleration_mps2 = config_.controlled_stop.linear_deceleration_mps2;
  loop_options.stop_angular_deceleration_radps2 =
      config_.controlled_stop.angular_deceleration_radps2;
  loop_options.twist_window_s = config_.twist_window_s;
  // Run samples only for the DDS topic that carries them.
  loop_options.run_sample_rate_hz = options_.dds ? dds_options_.run_samples_rate_hz : 0.0;
  rt::set_encoder_resolutions(config_.robot, loop_options);
  loop_options.external_sensors = dds::loop_sensor_options(dds_options_.ros2);
  loop_ = std::make_unique<rt::ControlLoop>(loop_options, *hardware_, hot_swap_->drivetrain(),
                                            hot_swap_->localization(),
                                            config_.localization.plugin.c_str());
  // inactive -> active, off the loop and before its first cycle.
  if (const std::string refusal = activate_hardware(*hardware_); !refusal.empty()) {
    loop_.reset();
    throw PluginError(config_.hardware.where + " plugin '" + config_.hardware.plugin +
                      "' refused to activate: " + refusal);
  }
  hardware_active_ = true;
  spdlog::info("hardware {} activated", config_.hardware.plugin);
  start_s_ = monotonic_s();
  std::set<std::string> seen;
  for (const auto& warning : loop_->start()) {
    if (seen.insert(warning).second) spdlog::warn("{}", warning);
  }
  spdlog::info("loop running at {} Hz: hardware {}, drivetrain {}, localization {}, robot {}",
               config_.rate_hz, config_.hardware.plugin, config_.drivetrain.plugin,
               config_.localization.plugin, config_.robot.name);
  hot_swap_->attach(loop_.get());
  loop_requests_ = std::make_unique<LoopRequests>(*loop_, *hardware_, config_.hardware.plugin);
  calibration_ = std::make_unique<CalibrationService>(
      config_, *loop_, loader_,
      [this](const dds::CalibrationSample& sample) { publish_calibration(sample); });
  if (config_.command.source == CommandSource::kScript) {
    script_ = std::make_unique<ScriptCommandSource>(*loop_, config_.command.script, start_s_);
    spdlog::info("command source: script of {} steps, played in a loop",
                 config_.command.script.size());
  }
  if (recorder_) {
    recorder_->start(*loop_);
    spdlog::info("recording the run log to {} at {} Hz", recorder_->path(),
                 options_.record_rate_hz);
  }
  if (options_.dds) start_bridge();
  if (options_.watch_config) {
    try {
      watcher_ = std::make_unique<ConfigWatcher>(config_.file, [this] { request_reload(); });
    } catch (const std::exception& e) {
      spdlog::warn("{}: configuration changes are not watched ({}); reload with SIGHUP",
                   config_.file, e.what());
    }
  }
  service_->start_watchdog(monotonic_s());
  service_->ready("running " + config_.robot.name + " at " +
                  std::to_string(static_cast<int>(config_.rate_hz)) + " Hz");
}

void Daemon::start_bridge() {
  diagnostics_ = std::make_unique<DiagnosticsSource>(
      *loop_, hardware_.name(), config_.drivetrain.plugin, start_s_, *reloads_);
  dds::DdsCallbacks callbacks;
  callbacks.read_state = [this](StateSnapshot& out) {
    out = loop_->latest();
    return out.cycle > 0;
  };
  // push_command has one producer: DDS commands drive the robot only when the daemon has no
  // command source of its own.
  if (config_.command.source == CommandSource::kNone) {
    // Refused (counted as dropped) once stop() began.
    callbacks.on_command = [this](const VelocityCommand& c) {
      return !stopping_.load(std::memory_order_acquire) && loop_->push_command(c);
    };
  } else {
    spdlog::info("DDS velocity commands are ignored: command.source is 'script'");
  }
  // Both motion-capture topics and the IMU are taken on the bridge's subscriber thread: the
  // rings' single producer.
  callbacks.on_motion_capture = [this](const MotionCaptureSample& m) {
    return loop_->push_motion_capture(m);
  };
  callbacks.on_pose_motion_capture = [this](const MotionCaptureSample& m) {
    return loop_->push_motion_capture(m, rt::MotionCaptureSource::kWatched);
  };
  callbacks.on_gyro = [this](const rt::GyroSample& g) { return loop_->push_gyro(g); };
  callbacks.read_diagnostics = [this] { return diagnostics_->read(); };
  // Answered on the main thread, one at a time, in the order they came.
  const auto queue = [this](RequestQueue::Request request) {
    if (auto busy = requests_->push(std::move(request)); busy && bridge_) {
      bridge_->publish_reply(*busy);
    }
  };
  callbacks.on_request = [queue](const dds::RequestSample& request) { queue(request); };
  callbacks.on_set_pose = [queue](const dds::SetPoseSample& pose) { queue(pose); };
  bridge_ =
      std::make_unique<dds::DdsBridge>(dds_options_, config_.robot.name, std::move(callbacks));
  bridge_->start();
  if (loop_->run_sample_period_s() > 0.0) {
    // The ring's only consumer: every sample the loop produced since its first cycle.
    run_samples_ = std::make_unique<dds::RunSamplePublisher>(
        bridge_->participant(), config_.robot.name, config_.robot.drivetrain,
        loop_->run_sample_period_s(),
        [this](RunSample& out) { return loop_->take_run_sample(out); });
    run_samples_->start();
    spdlog::info("DDS: run samples on {} at {:g} Hz", dds::kRunSamplesTopic,
                 1.0 / loop_->run_sample_period_s());
  }
  spdlog::info(
      "DDS: robot '{}' on domain {} ({}), state at {} Hz{}", config_.robot.name,
      dds_options_.domain_id, dds::resolve_config(dds_options_.config_uri).description,
      dds_options_.publish_rate_hz,
      dds_options_.ros2.enabled
          ? ", ROS 2 odometry on " + dds_options_.ros2.odom_topic() +
                (dds_options_.ros2.publish_tf ? ", " + swivel::dds::Ros2Options::tf_topic() : "") +
                ", " + dds_options_.ros2.joint_states_topic() + ", " +
                swivel::dds::Ros2Options::diagnostics_topic()
          : std::string());
  const auto& imu = dds_options_.ros2.imu;
  if (imu.enabled) {
    spdlog::info(
        "gyro from {} (sensor_msgs/Imu, mounting rpy [{}, {}, {}] rad), stale after "
        "{} s, {} s start-up grace",
        imu.dds_topic, imu.rotation_rpy_rad[0], imu.rotation_rpy_rad[1], imu.rotation_rpy_rad[2],
        imu.max_age_s, imu.startup_grace_s);
  }
  const auto& pose = dds_options_.ros2.mocap_pose;
  if (pose.enabled) {
    spdlog::info(
        "motion capture from {} (geometry_msgs/PoseStamped), stale after {} s, {} s "
        "start-up grace",
        pose.dds_topic, pose.max_age_s, pose.startup_grace_s);
  }
}

dds::ReplySample Daemon::handle_request(const dds::RequestSample& request) {
  if (!loop_requests_) {
    dds::ReplySample reply;
    reply.request_id = request.request_id;
    reply.verb = request.verb;
    reply.text = "refused: swiveld is not running";
    return reply;
  }
  return route_request(request, stopping_.load(std::memory_order_acquire), *handlers_);
}

dds::ReplySample Daemon::set_pose(const dds::SetPoseSample& request) {
  if (!loop_requests_) {
    dds::ReplySample reply;
    reply.request_id = request.request_id;
    reply.verb = "set_pose";
    reply.text = "refused: swiveld is not running";
    return reply;
  }
  return loop_requests_->set_pose(request, stopping_.load(std::memory_order_acquire));
}

void Daemon::publish_reply(const dds::ReplySample& reply) {
  if (bridge_) bridge_->publish_reply(reply);
}

void Daemon::publish_calibration(const dds::CalibrationSample& sample) noexcept {
  if (!bridge_) return;
  try {
    bridge_->publish_calibration(sample);
  } catch (const std::exception& e) {
    spdlog::error("calibration result not published: {}", e.what());
  }
}

void Daemon::stop() noexcept {
  const bool was_running = loop_ != nullptr;
  if (was_running) service_->stopping();
  // 1. No more commands: DDS commands are dropped from now on, the script stops, and the
  //    loop ignores whatever reaches it once the controlled stop began.
  stopping_.store(true, std::memory_order_release);
  script_.reset();
  // 2. The robot to rest while the loop runs, then the loop's final cycle (zero setpoints).
  //    A calibration is cancelled by the controlled stop; the runner takes it back below.
  if (loop_) {
    bring_to_rest(*loop_, config_.robot.limits, config_.controlled_stop);
    loop_->stop();
  }
  // 3. The drives off.
  if (hardware_active_) {
    hardware_active_ = false;
    hardware_stopped_ = deactivate_hardware(*hardware_, config_.hardware.plugin);
  }
  // 4. Only now everything around the loop. The bridge's threads stop before the runner is
  //    destroyed, since the runner publishes through the bridge.
  watcher_.reset();
  // After the loop's final cycle: the recorders get the whole run before the writer goes.
  if (run_samples_) {
    run_samples_->stop();
    const dds::RunSampleCounters c = run_samples_->counters();
    spdlog::info("DDS: {} run samples published, {} lost in the loop's ring, {} refused by DDS",
                 c.published, c.lost_at_source, c.write_failures);
  }
  run_samples_.reset();
  if (bridge_) bridge_->stop();
  calibration_.reset();
  bridge_.reset();
  diagnostics_.reset();
  if (recorder_) recorder_->stop();
  loop_requests_.reset();
  if (loop_) {
    (void)hot_swap_->collect();
    hot_swap_->attach(nullptr);
    loop_.reset();
  }
  hot_swap_->drop_incoming();  // a swap the loop never took: the instances were never used
  recorder_.reset();           // flushes the run log
}

ReloadResult Daemon::reload(const std::string& trigger) {
  ReloadResult result;
  service_->reloading("reloading " + config_.file);
  spdlog::info("reloading {} ({})", config_.file, trigger);
  try {
    DaemonConfig fresh = load_daemon_config(config_.file);
    dds::DdsOptions fresh_dds = dds::parse_dds_options(fresh.dds, fresh.file, fresh.config_dir);
    dds::complete_joints(fresh.robot, fresh.file, fresh_dds.ros2);
    std::string fresh_model_text = read_text(fresh.robot_model_path);
    const ReloadPlan plan = plan_reload(config_, robot_model_text_, fresh, fresh_model_text);

    std::vector<std::string> applied;
    if (plan.swap_localization || plan.swap_model) {
      if (plan.swap_model && calibration_ && calibration_->busy()) {
        throw PluginError("robot_model: a calibration is running; reload once it has ended");
      }
      // Applied first: a hand-over may refuse, and a new model waits for the robot at rest.
      const std::string outgoing = config_.localization.plugin;
      const HotSwap::Result swapped = apply_reload_swap(
          *hot_swap_, loader_, {config_, fresh, plan, loop_->latest().estimate, kSwapWaitS});
      if (plan.swap_model) {
        apply_robot_model(fresh, std::move(fresh_model_text));
        applied.push_back("robot_model " + config_.robot_model_path + " (drivetrain " +
                          config_.drivetrain.plugin + " and localization " +
                          fresh.localization.plugin + " rebuilt for it, taken at rest)");
      }
      if (plan.swap_localization) {
        applied.push_back(
            "localization " + outgoing + " -> " + fresh.localization.plugin +
            (outgoing == fresh.localization.plugin ? " (new parameters)" : "") +
            (swapped == HotSwap::Result::kPending ? " (not taken by the loop yet)" : ""));
      }
    }
    if (plan.log_level) {
      spdlog::set_level(spdlog::level::from_str(*plan.log_level));
      applied.push_back("logging.level " + *plan.log_level);
      config_.log_level = *plan.log_level;
    }
    if (plan.status_period_s) {
      status_period_s_ = *plan.status_period_s;
      config_.status_period_s = *plan.status_period_s;
      applied.emplace_back("status.period_s");
    }
    result.ok = true;
    result.restart_required = !plan.restart.empty();
    result.text = describe_reload(applied, plan.restart);
    spdlog::info("{}: reload {}", config_.file, result.text);
    if (!plan.restart.empty()) {
      spdlog::warn("{}: changed settings need a restart to take effect: {}", config_.file,
                   comma_list(plan.restart));
    }
  } catch (const std::exception& e) {
    result.ok = false;
    result.text = std::string("rejected: ") + e.what();
    spdlog::error("{}: configuration rejected, still running on the last good one: {}",
                  config_.file, e.what());
  }
  reloads_->record(result);
  service_->ready(result.ok ? "reloaded" : "reload rejected");
  return result;
}

// The loop took the new model: what reads it from the configuration follows (the controlled
// stop's limits at shutdown, the next calibration's nominal model and where it writes the
// calibrated one, the diagnostics).
void Daemon::apply_robot_model(const DaemonConfig& fresh, std::string text) {
  config_.robot_model_path = fresh.robot_model_path;
  config_.robot = fresh.robot;
  robot_model_text_ = std::move(text);
  reloads_->set_robot_model(config_.robot_model_path);
  if (calibration_) {
    calibration_ = std::make_unique<CalibrationService>(
        config_, *loop_, loader_,
        [this](const dds::CalibrationSample& sample) { publish_calibration(sample); });
  }
  spdlog::info("robot model {} ('{}') in effect", config_.robot_model_path, config_.robot.name);
}

int Daemon::run_until_signal(const sigset_t& signals) {
  constexpr double kTickS = 0.05;  // reload requests and retired instances are handled this often
  double next_status_s = monotonic_s() + status_period_s_;
  const auto publish = [this](const dds::ReplySample& reply) { publish_reply(reply); };
  for (;;) {
    service_->tick_watchdog(loop_.get(), monotonic_s());
    if (reload_requested_.exchange(false, std::memory_order_acq_rel)) {
      reload("configuration file changed or reload requested");
    }
    (void)hot_swap_->collect();
    answer_requests(*requests_, stopping_, *handlers_, publish);
    if (calibration_) calibration_->poll();
    double wait_s = std::min(kTickS, next_status_s - monotonic_s());
    if (const auto watchdog_s = service_->next_watchdog_s()) {
      wait_s = std::min(wait_s, *watchdog_s - monotonic_s());
    }
    const timespec timeout = to_timespec(std::max(0.0, wait_s));
    const int signal = sigtimedwait(&signals, nullptr, &timeout);
    if (signal == SIGHUP) {
      reload("SIGHUP");
    } else if (signal > 0) {
      // Stop first: the loop starts bringing the robot to rest in its next cycle, before
      // anything else is torn down (stop() does the rest).
      stopping_.store(true, std::memory_order_release);
      if (loop_) loop_->request_controlled_stop(monotonic_s());
      return signal;
    }
    if (monotonic_s() >= next_status_s) {
      std::fputs((status_line() + "\n").c_str(), stdout);
      std::fflush(stdout);
      next_status_s += status_period_s_;
      if (next_status_s < monotonic_s()) next_status_s = monotonic_s() + status_period_s_;
    }
  }
}

std::string Daemon::status_line() const {
  if (!loop_) return "not running";
  return format_status_line(loop_->latest(), loop_->timing(), start_s_);
}

}  // namespace swivel::daemon
