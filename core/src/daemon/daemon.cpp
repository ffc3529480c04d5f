#include "swivel/daemon/daemon.hpp"

#include <spdlog/spdlog.h>
#include <time.h>

#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <set>

#include <fstream>
#include <sstream>

#include "calibration_runner.hpp"
#include "config_watcher.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/rt/control_loop.hpp"
#include "swivel/run_log.hpp"

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

PluginContext plugin_context(const PluginConfig& slot, const DaemonConfig& config) {
  PluginContext ctx;
  ctx.params = slot.params;
  ctx.config_file = config.file;
  ctx.params_path = slot.params_path;
  ctx.config_dir = config.config_dir;
  ctx.robot = &config.robot;
  ctx.period_s = config.period_s();
  return ctx;
}

template <class Interface>
void configure_plugin(Interface& plugin, const PluginConfig& slot, const DaemonConfig& config) {
  const PluginContext ctx = plugin_context(slot, config);
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

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string dump(const YAML::Node& node) {
  if (!node || node.IsNull()) return "";
  YAML::Emitter out;
  out << node;
  return out.c_str();
}

bool same_slot(const PluginConfig& a, const PluginConfig& b) {
  return a.plugin == b.plugin && dump(a.params) == dump(b.params);
}

bool same_script(const std::vector<ScriptStep>& a, const std::vector<ScriptStep>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].duration_s != b[i].duration_s || a[i].twist.vx_mps != b[i].twist.vx_mps ||
        a[i].twist.vy_mps != b[i].twist.vy_mps || a[i].twist.wz_radps != b[i].twist.wz_radps) {
      return false;
    }
  }
  return true;
}

std::string join(const std::vector<std::string>& items) {
  std::string text;
  for (const auto& item : items) text += (text.empty() ? "" : ", ") + item;
  return text;
}

const char* drivetrain_name(DrivetrainKind kind) {
  return kind == DrivetrainKind::kSwpc ? "swpc" : "differential";
}

// Hardware::activate() with its exceptions caught: "" when it succeeded, else why not.
std::string activate_hardware(Hardware& hardware) {
  try {
    if (hardware.activate() == Status::kOk) return "";
    const std::string reason = hardware.last_error();
    return reason.empty() ? "no reason given" : reason;
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "unknown exception";
  }
}

bool finite_pose(const PoseEstimate& p) {
  if (!std::isfinite(p.pose.x_m) || !std::isfinite(p.pose.y_m) || !std::isfinite(p.pose.yaw_rad)) {
    return false;
  }
  if (!p.has_covariance) return true;
  for (const double v : p.covariance) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

std::string format(const char* pattern, double a, double b, double c) {
  char text[160];
  std::snprintf(text, sizeof text, pattern, a, b, c);
  return text;
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

struct Daemon::Recorder {
  std::unique_ptr<RunLogWriter> writer;
  std::string path;
};

Daemon::Daemon(DaemonConfig config, DaemonOptions options)
    : config_(std::move(config)),
      options_(std::move(options)),
      loader_(search_path(config_)),
      notifier_(service::Notifier::from_environment()) {
  dds_options_ = dds::parse_dds_options(config_.dds, config_.file, config_.config_dir);
  dds::complete_joints(config_.robot, config_.file, dds_options_.ros2);
  robot_model_text_ = read_text(config_.robot_model_path);
  status_period_s_ = config_.status_period_s;
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
  if (config_.has_calibration()) {
    // Configured once here so that a mistake in its params (or a robot it cannot calibrate)
    // stops the start-up like any other plugin's; each start creates a fresh instance.
    PluginInstance<Calibration> check = create_plugin<Calibration>(loader_, config_.calibration);
    configure_plugin(*check, config_.calibration, config_);
  }
  if (!(options_.record_rate_hz > 0.0 && options_.record_rate_hz <= 10000.0)) {
    throw ConfigError("--record-rate-hz: expected a rate in (0, 10000] Hz");
  }
}

Daemon::~Daemon() { stop(); }

void Daemon::start() {
  if (!options_.record_path.empty()) {
    recorder_ = std::make_unique<Recorder>();
    recorder_->path = options_.record_path;
    RunLogHeader header = run_log_header(config_.robot);
    header.comments.push_back("recorded by swiveld from " + config_.file + " at " +
                              std::to_string(options_.record_rate_hz) + " Hz");
    recorder_->writer = std::make_unique<RunLogWriter>(options_.record_path, header);
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
  rt::set_encoder_resolutions(config_.robot, loop_options);
  loop_ = std::make_unique<rt::ControlLoop>(loop_options, *hardware_, *drivetrain_,
                                            *localization_, config_.localization.plugin.c_str());
  // inactive -> active, off the loop and before its first cycle.
  if (const std::string refusal = activate_hardware(*hardware_); !refusal.empty()) {
    loop_.reset();
    throw PluginError(config_.hardware.where + " plugin '" + config_.hardware.plugin +
                      "' refused to activate: " + refusal);
  }
  hardware_active_ = true;
  spdlog::info("hardware {} activated", config_.hardware.plugin);
  start_s_ = monotonic_now_s();
  std::set<std::string> seen;
  for (const auto& warning : loop_->start()) {
    if (seen.insert(warning).second) spdlog::warn("{}", warning);
  }
  spdlog::info("loop running at {} Hz: hardware {}, drivetrain {}, localization {}, robot {}",
               config_.rate_hz, config_.hardware.plugin, config_.drivetrain.plugin,
               config_.localization.plugin, config_.robot.name);
  if (config_.has_calibration()) {
    // The runner calls back with its mutex held, from the thread that called it (the DDS
    // subscriber or the main thread), never from the loop.
    calibration_ = std::make_unique<CalibrationRunner>(
        *loop_, loader_, config_.robot, config_.robot_model_path, plugin_context(config_.calibration, config_),
        config_.calibration.plugin, [this](const dds::CalibrationSample& sample) {
          if (sample.status != calibration_logged_ || sample.status != "running") {
            if (sample.status == "failed") {
              spdlog::error("calibration failed: {}", sample.text);
            } else {
              spdlog::info("calibration {}: {}", sample.status, sample.text);
            }
            calibration_logged_ = sample.status;
          }
          publish_calibration(sample);
        });
    spdlog::info("calibration: plugin {} ready (swivelctl calibrate start); calibrated models "
                 "are written next to {}",
                 config_.calibration.plugin, config_.robot_model_path);
  }
  if (config_.command.source == CommandSource::kScript) {
    command_thread_ = std::jthread([this](const std::stop_token& stop) { run_script(stop); });
    spdlog::info("command source: script of {} steps, played in a loop",
                 config_.command.script.size());
  }
  if (recorder_) {
    recorder_thread_ = std::jthread([this](const std::stop_token& stop) { run_recorder(stop); });
    spdlog::info("recording the run log to {} at {} Hz", recorder_->path, options_.record_rate_hz);
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
  watchdog_interval_ = service::watchdog_interval_from_environment();
  if (notifier_.enabled()) {
    notifier_.ready("running " + config_.robot.name + " at " +
                    std::to_string(static_cast<int>(config_.rate_hz)) + " Hz");
  }
}

void Daemon::start_bridge() {
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
  callbacks.on_motion_capture = [this](const MotionCaptureSample& m) {
    return loop_->push_motion_capture(m);
  };
  callbacks.read_diagnostics = [this] { return read_diagnostics(); };
  // Answered on the main thread, one at a time, in the order they came.
  callbacks.on_request = [this](const dds::RequestSample& request) { queue_request(request); };
  callbacks.on_set_pose = [this](const dds::SetPoseSample& pose) { queue_request(pose); };
  bridge_ = std::make_unique<dds::DdsBridge>(dds_options_, config_.robot.name,
                                             std::move(callbacks));
  bridge_->start();
  spdlog::info("DDS: robot '{}' on domain {} ({}), state at {} Hz{}", config_.robot.name,
               dds_options_.domain_id, dds::resolve_config(dds_options_.config_uri).description,
               dds_options_.publish_rate_hz,
               dds_options_.ros2.enabled
                   ? ", ROS 2 odometry on " + dds_options_.ros2.odom_topic() +
                         (dds_options_.ros2.publish_tf ? ", " + dds_options_.ros2.tf_topic() : "") +
                         ", " + dds_options_.ros2.joint_states_topic() + ", " +
                         dds_options_.ros2.diagnostics_topic()
                   : std::string());
}

std::string Daemon::calibration_refusal() const {
  if (config_.robot.drivetrain != DrivetrainKind::kSwpc) {
    return std::string("refused: robot '") + config_.robot.name + "' has a " +
           drivetrain_name(config_.robot.drivetrain) +
           " drivetrain; the calibration (swpc_geometric) needs an swpc robot, and " +
           config_.file + " has no calibration: section";
  }
  return "refused: no calibration configured: add 'calibration: {plugin: swpc_geometric}' to " +
         config_.file + " and restart swiveld";
}

void Daemon::queue_request(PendingRequest request) {
  constexpr std::size_t kMaxPending = 64;
  {
    const std::lock_guard lock(requests_mutex_);
    if (pending_requests_.size() < kMaxPending) {
      pending_requests_.push_back(std::move(request));
      return;
    }
  }
  // A flood of requests: answer the newest at once rather than queue without bound.
  dds::ReplySample busy;
  if (const auto* r = std::get_if<dds::RequestSample>(&request)) {
    busy.request_id = r->request_id;
    busy.verb = r->verb;
  } else {
    const auto& p = std::get<dds::SetPoseSample>(request);
    if (!p.wants_reply) return;
    busy.request_id = p.request_id;
    busy.verb = "set_pose";
  }
  busy.text = "refused: " + std::to_string(kMaxPending) + " requests are waiting; try again";
  if (bridge_) bridge_->publish_reply(busy);
}

void Daemon::process_requests() {
  for (;;) {
    PendingRequest next;
    {
      const std::lock_guard lock(requests_mutex_);
      if (pending_requests_.empty()) return;
      next = std::move(pending_requests_.front());
      pending_requests_.pop_front();
    }
    dds::ReplySample reply;
    bool wants_reply = true;
    if (const auto* r = std::get_if<dds::RequestSample>(&next)) {
      reply = handle_request(*r);
    } else {
      const auto& p = std::get<dds::SetPoseSample>(next);
      reply = set_pose(p);
      wants_reply = p.wants_reply;
    }
    if (!wants_reply || !bridge_) continue;
    try {
      bridge_->publish_reply(reply);
    } catch (const std::exception& e) {
      spdlog::error("reply to {} request {} not published: {}", reply.verb, reply.request_id,
                    e.what());
    }
  }
}

dds::ReplySample Daemon::handle_request(const dds::RequestSample& request) {
  dds::ReplySample reply;
  if (stopping_.load(std::memory_order_acquire)) {
    reply.text = "refused: swiveld is stopping";
  } else if (request.verb == "reload") {
    const ReloadResult result = reload("reload request");
    reply.ok = result.ok;
    reply.text = result.text;
  } else if (request.verb == "clear") {
    reply = clear_fault(request.request_id);
  } else if (request.verb == "calibrate") {
    reply = calibrate(request.argument);
  } else {
    reply.text = "refused: unknown request '" + request.verb +
                 "' (reload, clear, calibrate; a pose goes to " + dds::kSetPoseTopic + ")";
  }
  reply.request_id = request.request_id;
  reply.verb = request.verb;
  if (reply.ok) {
    spdlog::info("{} request {}: {}", request.verb, request.request_id, reply.text);
  } else {
    spdlog::warn("{} request {}: {}", request.verb, request.request_id, reply.text);
  }
  return reply;
}

bool Daemon::wait_for_loop_reply(std::uint64_t id, rt::LoopReply& out) {
  // The loop answers at its next cycle; a second covers a stalled or very slow loop.
  const double deadline_s = monotonic_now_s() + 1.0;
  while (monotonic_now_s() < deadline_s && loop_->running()) {
    if (loop_->take_reply(out) && out.id == id) return true;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  return false;
}

dds::ReplySample Daemon::clear_fault(std::uint64_t request_id) {
  dds::ReplySample reply;
  reply.request_id = request_id;
  reply.verb = "clear";
  if (loop_->latest().hardware_in_error) {
    // The hardware left its active state: activate it again off the loop, with the loop's
    // calls to it paused at a cycle boundary (granted once the robot stands still).
    // Short: the main thread also keeps systemd's watchdog (2 s) fed.
    constexpr double kPauseTimeoutS = 1.0;
    if (!loop_->pause_hardware(kPauseTimeoutS)) {
      reply.text =
          "refused: hardware_error: the hardware could not be paused for re-activation "
          "(the robot has not come to rest: its last setpoints were not zero); try again";
      return reply;
    }
    const std::string refusal = activate_hardware(*hardware_);
    loop_->resume_hardware();
    if (!refusal.empty()) {
      reply.text = "refused: hardware plugin '" + config_.hardware.plugin +
                   "' refused to re-activate: " + refusal;
      return reply;
    }
    spdlog::info("hardware {} re-activated", config_.hardware.plugin);
  }
  const std::uint64_t id = ++loop_request_id_;
  loop_->request_clear(id);
  rt::LoopReply answer;
  if (!wait_for_loop_reply(id, answer)) {
    reply.text = "refused: the real-time loop did not answer within 1 s";
    return reply;
  }
  const std::string fault = fault_code_name(answer.fault);
  const std::string cause = answer.detail.data();
  reply.ok = answer.ok;
  if (answer.ok) {
    reply.text = answer.fault == FaultCode::kNone ? "nothing to clear"
                                                  : "cleared " + fault + " (" + cause + ")";
  } else if (answer.fault == FaultCode::kCommandTimeout) {
    reply.text = "refused: " + fault + " persists (" + cause +
                 "): no fresh velocity command; the next one resumes by itself";
  } else {
    reply.text = "refused: " + fault + " persists (" + cause + ")";
  }
  return reply;
}

dds::ReplySample Daemon::set_pose(const dds::SetPoseSample& request) {
  dds::ReplySample reply;
  reply.request_id = request.request_id;
  reply.verb = "set_pose";
  const PoseEstimate& p = request.pose;
  const auto& c = p.covariance;
  if (stopping_.load(std::memory_order_acquire)) {
    reply.text = "refused: swiveld is stopping";
  } else if (!finite_pose(p)) {
    reply.text = "refused: the pose (x_m, y_m, yaw_rad) and its covariance must be finite";
  } else if (p.has_covariance && (c[0] < 0.0 || c[4] < 0.0 || c[8] < 0.0)) {
    reply.text = "refused: negative variance (x " + std::to_string(c[0]) + " m^2, y " +
                 std::to_string(c[4]) + " m^2, yaw " + std::to_string(c[8]) + " rad^2)";
  } else {
    const std::uint64_t id = ++loop_request_id_;
    loop_->request_set_pose(p, id);
    rt::LoopReply answer;
    const std::string plugin = loop_->latest().localization_plugin.data();
    if (!wait_for_loop_reply(id, answer)) {
      reply.text = "refused: the real-time loop did not answer within 1 s";
    } else if (!answer.ok) {
      reply.text = "refused by localization '" + plugin + "': " + answer.detail.data();
    } else {
      reply.ok = true;
      reply.text = format("pose set to x=%.3f m y=%.3f m yaw=%.3f rad", p.pose.x_m, p.pose.y_m,
                          p.pose.yaw_rad) +
                   (p.has_covariance ? format(", sigma x=%.3g m y=%.3g m yaw=%.3g rad",
                                              std::sqrt(c[0]), std::sqrt(c[4]), std::sqrt(c[8]))
                                     : std::string(", uncertainty kept")) +
                   " (localization " + plugin + ")";
    }
  }
  if (reply.ok) {
    spdlog::info("set pose from {}: {}", request.source, reply.text);
  } else {
    spdlog::warn("set pose from {}: {}", request.source, reply.text);
  }
  return reply;
}

dds::ReplySample Daemon::calibrate(const std::string& argument) {
  dds::ReplySample reply;
  reply.verb = "calibrate";
  spdlog::info("calibrate {} requested", argument.empty() ? "status" : argument);
  if (!calibration_) {
    dds::CalibrationSample answer;
    answer.status = "failed";
    answer.text = calibration_refusal();
    publish_calibration(answer);
    reply.text = answer.text;
    return reply;
  }
  try {
    if (argument == "start") {
      const std::string refusal = calibration_->start();  // publishes either way
      reply.ok = refusal.empty();
      reply.text = reply.ok ? "calibration started" : "refused: " + refusal;
    } else if (argument == "cancel" || argument == "status" || argument.empty()) {
      calibration_->handle_request(argument);
      const dds::CalibrationSample status = calibration_->status();
      reply.ok = true;
      reply.text = (argument == "cancel" ? "cancel requested; " : "") + status.status + ": " +
                   status.text;
    } else {
      calibration_->handle_request(argument);
      reply.text = "refused: unknown calibrate argument '" + argument +
                   "' (start | cancel | status)";
    }
  } catch (const std::exception& e) {
    reply.text = "refused: " + std::string(e.what());
  }
  return reply;
}

void Daemon::publish_calibration(const dds::CalibrationSample& sample) noexcept {
  if (!bridge_) return;
  try {
    bridge_->publish_calibration(sample);
  } catch (const std::exception& e) {
    spdlog::error("calibration result not published: {}", e.what());
  }
}

void Daemon::poll_calibration() noexcept {
  if (!calibration_) return;
  try {
    calibration_->poll();
  } catch (const std::exception& e) {
    spdlog::error("calibration: {}", e.what());
  }
}

dds::DiagnosticsSample Daemon::read_diagnostics() {
  dds::DiagnosticsSample d;
  const auto timing = loop_->timing();
  const StateSnapshot s = loop_->latest();
  const double now = monotonic_now_s();
  d.uptime_s = now - start_s_;
  d.loop_rate_hz = 1.0 / loop_->period_s();
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
  // Hardware and drivetrain never change while running; the localization is the loop's.
  d.hardware_plugin = hardware_.name();
  d.drivetrain_plugin = drivetrain_.name();
  d.localization_plugin = s.localization_plugin.data();
  std::lock_guard lock(reload_mutex_);
  d.reload_count = reload_count_;
  d.last_reload_ok = last_reload_.ok;
  d.last_reload_result = last_reload_.text;
  d.restart_required = restart_required_;
  return d;
}

// The controlled stop: commands ignored, the twist ramped to zero within the stop's limits
// while the loop runs; waits until the robot stands still, or a bound on the ramp's time.
void Daemon::bring_to_rest() noexcept {
  if (!loop_ || !loop_->running()) return;
  loop_->request_controlled_stop(monotonic_now_s());  // no-op when the signal asked already
  try {
    const StateSnapshot from = loop_->latest();
    const MotionLimits& limits = config_.robot.limits;
    const double a_linear =
        limits.linear_acceleration_mps2.value_or(config_.controlled_stop.linear_deceleration_mps2);
    const double a_angular = limits.angular_acceleration_radps2.value_or(
        config_.controlled_stop.angular_deceleration_radps2);
    const Twist2& v = from.command_twist;
    double ramp_s = std::max({std::abs(v.vx_mps) / a_linear, std::abs(v.vy_mps) / a_linear,
                              std::abs(v.wz_radps) / a_angular});
    if (limits.linear_jerk_mps3) ramp_s += a_linear / *limits.linear_jerk_mps3;
    if (limits.angular_jerk_radps3) ramp_s += a_angular / *limits.angular_jerk_radps3;
    const double limit_s = ramp_s + 1.0;  // and the drives' own lag
    spdlog::info("stopping: bringing the robot to rest from vx={:.3f} m/s vy={:.3f} m/s "
                 "wz={:.3f} rad/s (controlled stop at {} m/s^2, {} rad/s^2)",
                 v.vx_mps, v.vy_mps, v.wz_radps, a_linear, a_angular);
    const double start_s = monotonic_now_s();
    for (;;) {
      const StateSnapshot s = loop_->latest();
      const Twist2& c = s.command_twist;
      const Twist2& m = s.odometry_twist;
      const bool commanded_zero = c.vx_mps == 0.0 && c.vy_mps == 0.0 && c.wz_radps == 0.0;
      const bool measured_still =
          std::hypot(m.vx_mps, m.vy_mps) < 0.005 && std::abs(m.wz_radps) < 0.01;
      if (s.stopping && commanded_zero && measured_still) {
        if (s.has_truth && from.has_truth) {
          spdlog::info("robot at rest after {:.3f} s; it travelled {:.4f} m meanwhile "
                       "(simulator's ground truth)",
                       s.stamp_s - from.stamp_s,
                       std::hypot(s.truth.x_m - from.truth.x_m, s.truth.y_m - from.truth.y_m));
        } else {
          spdlog::info("robot at rest after {:.3f} s", s.stamp_s - from.stamp_s);
        }
        return;
      }
      if (monotonic_now_s() - start_s > limit_s || !loop_->running()) {
        spdlog::error("the robot did not come to rest within {:.2f} s; stopping the loop anyway "
                      "(zero setpoints at once)",
                      limit_s);
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  } catch (const std::exception& e) {
    try {
      spdlog::error("controlled stop: {}", e.what());
    } catch (...) {
    }
  }
}

void Daemon::deactivate_hardware() noexcept {
  if (!hardware_active_) return;
  hardware_active_ = false;
  try {
    std::string failure;
    try {
      if (hardware_->deactivate() != Status::kOk) {
        failure = hardware_->last_error();
        if (failure.empty()) failure = "no reason given";
      }
    } catch (const std::exception& e) {
      failure = e.what();
    }
    if (failure.empty()) {
      spdlog::info("hardware {} deactivated", config_.hardware.plugin);
    } else {
      spdlog::error("hardware {} failed to deactivate: {}", config_.hardware.plugin, failure);
    }
  } catch (...) {
  }
}

void Daemon::stop() noexcept {
  const bool was_running = loop_ != nullptr;
  if (was_running && notifier_.enabled()) {
    try {
      notifier_.stopping();
    } catch (...) {
    }
  }
  // 1. No more commands: DDS commands are dropped from now on, the script stops, and the
  //    loop ignores whatever reaches it once the controlled stop began.
  stopping_.store(true, std::memory_order_release);
  if (command_thread_.joinable()) {
    command_thread_.request_stop();
    command_thread_.join();
  }
  // 2. The robot to rest while the loop runs, then the loop's final cycle (zero setpoints).
  //    A calibration is cancelled by the controlled stop; the runner takes it back below.
  if (loop_) {
    bring_to_rest();
    loop_->stop();
  }
  // 3. The drives off.
  deactivate_hardware();
  // 4. Only now everything around the loop. The bridge's threads stop before the runner is
  //    destroyed, since the runner publishes through the bridge.
  watcher_.reset();
  if (bridge_) bridge_->stop();
  calibration_.reset();
  bridge_.reset();
  if (recorder_thread_.joinable()) {
    recorder_thread_.request_stop();
    recorder_thread_.join();
  }
  if (loop_) {
    (void)collect_retired_localization();
    loop_.reset();
  }
  incoming_.reset();  // a swap the loop never took: the instance was never used
  if (recorder_) {
    try {
      recorder_->writer->flush();
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
    }
    recorder_.reset();
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

void Daemon::run_recorder(const std::stop_token& stop) {
  const auto period = std::chrono::duration<double>(1.0 / options_.record_rate_hz);
  const bool differential = config_.robot.drivetrain == DrivetrainKind::kDifferential;
  const std::size_t modules = config_.robot.module_count();
  std::uint64_t last_cycle = 0;
  double t0 = -1.0;
  auto next = std::chrono::steady_clock::now();
  auto next_flush = next + std::chrono::seconds(1);
  std::mutex mutex;
  std::condition_variable_any wake;
  std::unique_lock lock(mutex);
  while (!stop.stop_requested()) {
    const StateSnapshot s = loop_->latest();
    if (s.cycle > last_cycle) {
      last_cycle = s.cycle;
      if (t0 < 0.0) t0 = s.stamp_s;
      RunLogSample row;
      row.t_s = s.stamp_s - t0;
      row.cmd = s.command_twist;
      for (std::size_t i = 0; i < modules && i < kMaxModules; ++i) {
        row.wheel_rad[i] = s.wheel_angle_rad[i];
        if (!differential) row.steer_rad[i] = s.steer_angle_rad[i];
      }
      row.gyro_wz_radps = s.gyro_wz_radps;
      row.has_truth = s.has_truth;
      row.truth = s.truth;
      try {
        recorder_->writer->write(row);
        if (std::chrono::steady_clock::now() >= next_flush) {
          recorder_->writer->flush();
          next_flush += std::chrono::seconds(1);
        }
      } catch (const std::exception& e) {
        spdlog::error("run log {}: {}; recording stopped", recorder_->path, e.what());
        return;
      }
    }
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    wake.wait_until(lock, stop, next, [] { return false; });
  }
}

Daemon::SwapResult Daemon::collect_retired_localization(std::string* refusal) noexcept {
  if (!loop_ || !incoming_) return SwapResult::kPending;
  rt::SwapOutcome outcome;
  Localization* retired = loop_->take_retired_localization(&outcome);
  if (retired == nullptr) return SwapResult::kPending;
  if (!outcome.taken && retired == incoming_.get()) {
    // Rolled back: the loop kept the active instance and never used this one.
    if (refusal != nullptr) *refusal = outcome.refusal.data();
    incoming_.reset();
    return SwapResult::kRefused;
  }
  if (outcome.taken && retired == localization_.get()) {
    // The loop let go of the outgoing instance: destroy it, then its library may unload.
    localization_ = std::move(incoming_);
    config_.localization = incoming_slot_;
    return SwapResult::kTaken;
  }
  try {
    spdlog::error("hot swap: the loop retired an unexpected localization instance");
  } catch (...) {
  }
  return SwapResult::kPending;
}

ReloadResult Daemon::reload(const std::string& trigger) {
  ReloadResult result;
  if (notifier_.enabled()) notifier_.reloading("reloading " + config_.file);
  spdlog::info("reloading {} ({})", config_.file, trigger);
  PluginInstance<Localization> next;
  try {
    DaemonConfig fresh = load_daemon_config(config_.file);
    dds::DdsOptions fresh_dds = dds::parse_dds_options(fresh.dds, fresh.file, fresh.config_dir);
    dds::complete_joints(fresh.robot, fresh.file, fresh_dds.ros2);

    std::vector<std::string> restart;
    if (fresh.rate_hz != config_.rate_hz) restart.push_back("loop.rate_hz");
    if (fresh.fifo_priority != config_.fifo_priority) restart.push_back("loop.fifo_priority");
    if (fresh.realtime != config_.realtime) restart.push_back("loop.realtime");
    if (fresh.robot_model_path != config_.robot_model_path ||
        read_text(fresh.robot_model_path) != robot_model_text_) {
      restart.push_back("robot_model");
    }
    if (!same_slot(fresh.hardware, config_.hardware)) restart.push_back("hardware");
    if (!same_slot(fresh.drivetrain, config_.drivetrain)) restart.push_back("drivetrain");
    if (fresh.command.timeout_s != config_.command.timeout_s ||
        fresh.command.source != config_.command.source ||
        !same_script(fresh.command.script, config_.command.script)) {
      restart.push_back("command");
    }
    if (fresh.plugin_path != config_.plugin_path) restart.push_back("plugin_path");
    if (dump(fresh.dds) != dump(config_.dds)) restart.push_back("dds");
    if (!same_slot(fresh.calibration, config_.calibration)) restart.push_back("calibration");
    if (fresh.controlled_stop.linear_deceleration_mps2 !=
            config_.controlled_stop.linear_deceleration_mps2 ||
        fresh.controlled_stop.angular_deceleration_radps2 !=
            config_.controlled_stop.angular_deceleration_radps2) {
      restart.push_back("controlled_stop");
    }
    if (fresh.twist_window_s != config_.twist_window_s) restart.push_back("odometry");

    std::vector<std::string> applied;
    const bool swap = !same_slot(fresh.localization, config_.localization);
    if (swap) {
      (void)collect_retired_localization();
      if (incoming_ || loop_->swap_pending()) {
        throw PluginError("the previous localization swap has not completed yet; try again");
      }
      // Built and validated in full before anything changes; the robot model stays the one
      // in effect (a changed model needs a restart).
      next = create_plugin<Localization>(loader_, fresh.localization);
      PluginContext ctx;
      ctx.params = fresh.localization.params;
      ctx.config_file = fresh.file;
      ctx.params_path = fresh.localization.params_path;
      ctx.config_dir = fresh.config_dir;
      ctx.robot = &config_.robot;
      ctx.period_s = config_.period_s();
      try {
        next->configure(ctx);
      } catch (const ConfigError& e) {
        throw ConfigError(e.what());
      } catch (const std::exception& e) {
        throw PluginError(fresh.localization.where + " plugin '" + fresh.localization.plugin +
                          "' failed to configure: " + e.what());
      }
      next->reset(loop_->latest().estimate);
    }

    // Everything validated: apply. The localization first: its hand-over may refuse.
    if (swap) {
      const std::string outgoing = config_.localization.plugin;
      incoming_ = std::move(next);
      incoming_slot_ = fresh.localization;
      if (!loop_->request_localization_swap(incoming_.get(), fresh.localization.plugin.c_str())) {
        incoming_.reset();
        throw PluginError("the loop refused the localization swap (one is still pending)");
      }
      // The loop takes it, or rolls it back, at its next cycle boundary.
      const double deadline = monotonic_now_s() + 2.0;
      std::string refusal;
      SwapResult swapped = SwapResult::kPending;
      while (swapped == SwapResult::kPending && monotonic_now_s() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        swapped = collect_retired_localization(&refusal);
      }
      if (swapped == SwapResult::kRefused) {
        throw PluginError(fresh.localization.where + " plugin '" + fresh.localization.plugin +
                          "' refused the hand-over: " + refusal + "; '" + outgoing +
                          "' stays active");
      }
      applied.push_back("localization " + outgoing + " -> " + fresh.localization.plugin +
                        (outgoing == fresh.localization.plugin ? " (new parameters)" : "") +
                        (swapped == SwapResult::kPending ? " (not taken by the loop yet)" : ""));
    }
    if (fresh.log_level != config_.log_level) {
      spdlog::set_level(spdlog::level::from_str(fresh.log_level));
      applied.push_back("logging.level " + fresh.log_level);
      config_.log_level = fresh.log_level;
    }
    if (fresh.status_period_s != config_.status_period_s) {
      status_period_s_ = fresh.status_period_s;
      config_.status_period_s = fresh.status_period_s;
      applied.push_back("status.period_s");
    }
    result.ok = true;
    result.restart_required = !restart.empty();
    result.text = applied.empty() ? "no live change" : "applied " + join(applied);
    if (!restart.empty()) result.text += "; needs a restart: " + join(restart);
    spdlog::info("{}: reload {}", config_.file, result.text);
    if (!restart.empty()) {
      spdlog::warn("{}: changed settings need a restart to take effect: {}", config_.file,
                   join(restart));
    }
  } catch (const std::exception& e) {
    next.reset();
    result.ok = false;
    result.text = std::string("rejected: ") + e.what();
    spdlog::error("{}: configuration rejected, still running on the last good one: {}",
                  config_.file, e.what());
  }
  {
    std::lock_guard lock(reload_mutex_);
    ++reload_count_;
    last_reload_ = result;
    if (result.ok) restart_required_ = result.restart_required;
  }
  if (notifier_.enabled()) notifier_.ready(result.ok ? "reloaded" : "reload rejected");
  return result;
}

void Daemon::send_watchdog_if_healthy() {
  if (!loop_ || !notifier_.enabled()) return;
  // Healthy means the loop has run cycles since the last ping; a stalled loop lets systemd's
  // watchdog fire.
  const std::uint64_t cycle = loop_->latest().cycle;
  if (cycle > watchdog_cycle_ && loop_->running()) notifier_.watchdog();
  watchdog_cycle_ = cycle;
}

int Daemon::run_until_signal(const sigset_t& signals) {
  constexpr double kTickS = 0.05;  // reload requests and retired instances are handled this often
  double next_status_s = monotonic_now_s() + status_period_s_;
  const double watchdog_period_s =
      watchdog_interval_ ? static_cast<double>(watchdog_interval_->count()) * 1e-6 / 2.0 : 0.0;
  double next_watchdog_s = monotonic_now_s();
  for (;;) {
    const double now = monotonic_now_s();
    if (watchdog_interval_ && now >= next_watchdog_s) {
      send_watchdog_if_healthy();
      next_watchdog_s = now + watchdog_period_s;
    }
    if (reload_requested_.exchange(false, std::memory_order_acq_rel)) {
      reload("configuration file changed or reload requested");
    }
    (void)collect_retired_localization();
    process_requests();
    poll_calibration();
    double wait_s = std::min(kTickS, next_status_s - monotonic_now_s());
    if (watchdog_interval_) wait_s = std::min(wait_s, next_watchdog_s - monotonic_now_s());
    const timespec timeout = to_timespec(std::max(0.0, wait_s));
    const int signal = sigtimedwait(&signals, nullptr, &timeout);
    if (signal == SIGHUP) {
      reload("SIGHUP");
    } else if (signal > 0) {
      // Stop first: the loop starts bringing the robot to rest in its next cycle, before
      // anything else is torn down (stop() does the rest).
      stopping_.store(true, std::memory_order_release);
      if (loop_) loop_->request_controlled_stop(monotonic_now_s());
      return signal;
    }
    if (monotonic_now_s() >= next_status_s) {
      std::fputs((status_line() + "\n").c_str(), stdout);
      std::fflush(stdout);
      next_status_s += status_period_s_;
      if (next_status_s < monotonic_now_s()) next_status_s = monotonic_now_s() + status_period_s_;
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
