// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/control_loop.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <span>
#include <stdexcept>
#include <system_error>

#include "swivel/rt/finite.hpp"

namespace swivel::rt {
namespace {

TwistWindowOptions twist_window_options(const LoopOptions& options) {
  TwistWindowOptions o;
  o.readings = twist_window_readings(options);
  o.wheel_resolution_rad = options.wheel_encoder_resolution_rad;
  o.steer_resolution_rad = options.steer_encoder_resolution_rad;
  return o;
}

}  // namespace

std::size_t twist_window_readings(const LoopOptions& options) {
  // An invalid rate is the constructor's to report.
  if (!std::isfinite(options.rate_hz) || !(options.rate_hz > 0.0)) return 2;
  const double periods = options.twist_window_s * options.rate_hz;
  if (!std::isfinite(periods) || !(options.twist_window_s > 0.0) ||
      periods > static_cast<double>(kMaxTwistWindowReadings - 1)) {
    throw std::invalid_argument("twist_window_s must be finite, positive and at most " +
                                std::to_string(kMaxTwistWindowReadings - 1) +
                                " loop periods, got " + std::to_string(options.twist_window_s) +
                                " s at " + std::to_string(options.rate_hz) + " Hz");
  }
  return std::max<std::size_t>(2, static_cast<std::size_t>(std::llround(periods)) + 1);
}

void set_encoder_resolutions(const RobotModel& robot, LoopOptions& options) noexcept {
  const SensorParams& sensors = robot.sensors;
  options.wheel_encoder_resolution_rad =
      sensors.wheel_encoder_counts_per_rev > 0
          ? 2.0 * std::numbers::pi / sensors.wheel_encoder_counts_per_rev
          : 0.0;
  options.steer_encoder_resolution_rad =
      robot.drivetrain == DrivetrainKind::kSwpc && sensors.steering_encoder_counts_per_rev > 0
          ? 2.0 * std::numbers::pi / sensors.steering_encoder_counts_per_rev
          : 0.0;
}

ModelSettings model_settings(const RobotModel& robot) noexcept {
  LoopOptions options;
  set_encoder_resolutions(robot, options);
  ModelSettings model;
  model.limits = robot.limits;
  model.wheel_encoder_resolution_rad = options.wheel_encoder_resolution_rad;
  model.steer_encoder_resolution_rad = options.steer_encoder_resolution_rad;
  return model;
}

ControlLoop::ControlLoop(const LoopOptions& options, Hardware& hardware, Drivetrain& drivetrain,
                         Localization& localization, const char* localization_name)
    : options_(options),
      period_s_(1.0 / options.rate_hz),
      period_ns_(std::llround(1e9 / options.rate_hz)),
      hardware_(hardware),
      drivetrain_(&drivetrain),
      module_count_(std::min(drivetrain.module_count(), kMaxModules)),
      timing_(1.0 / options.rate_hz),
      swap_(localization, localization_name),
      sensors_(options.external_sensors),
      odometry_(options.odometry_check, twist_window_options(options)),
      command_(CommandLimits{options.limits, options.stop_linear_deceleration_mps2,
                             options.stop_angular_deceleration_radps2, options.command_timeout_s,
                             1.0 / options.rate_hz}),
      write_(module_count_, 1.0 / options.rate_hz),
      publish_(options.run_sample_rate_hz > 0.0 ? 1.0 / options.run_sample_rate_hz : 0.0,
               1.0 / options.rate_hz) {
  if (!std::isfinite(options.rate_hz) || options.rate_hz <= 0.0 || period_ns_ <= 0) {
    throw std::invalid_argument("loop rate_hz must be finite and positive, got " +
                                std::to_string(options.rate_hz));
  }
  if (!std::isfinite(options.command_timeout_s) || options.command_timeout_s <= 0.0) {
    throw std::invalid_argument("command timeout_s must be finite and positive, got " +
                                std::to_string(options.command_timeout_s));
  }
  if (!std::isfinite(options.clock_offset_refresh_s) || !(options.clock_offset_refresh_s > 0.0)) {
    throw std::invalid_argument("clock_offset_refresh_s must be finite and positive, got " +
                                std::to_string(options.clock_offset_refresh_s));
  }
  for (const std::string& problem :
       {validate(options.external_sensors.gyro, "external gyro"),
        validate(options.external_sensors.motion_capture, "external motion capture")}) {
    if (!problem.empty()) throw std::invalid_argument(problem);
  }
  if (!OdometryMonitor::valid(options.odometry_check)) {
    throw std::invalid_argument(
        "odometry_check: gyro_disagreement_radps, residual_limit_mps, filter_time_constant_s "
        "and persistence_s must be finite and positive, gyro_disagreement_fraction >= 0");
  }
  if (!(options.stop_linear_deceleration_mps2 > 0.0) ||
      !(options.stop_angular_deceleration_radps2 > 0.0)) {
    throw std::invalid_argument(
        "controlled stop decelerations must be positive (infinite: stop at once), got " +
        std::to_string(options.stop_linear_deceleration_mps2) + " m/s^2 and " +
        std::to_string(options.stop_angular_deceleration_radps2) + " rad/s^2");
  }
  if (!std::isfinite(options.run_sample_rate_hz) || options.run_sample_rate_hz < 0.0 ||
      options.run_sample_rate_hz > options.rate_hz) {
    throw std::invalid_argument(
        "run_sample_rate_hz must be 0 (none) or positive and at most "
        "the loop rate " +
        std::to_string(options.rate_hz) + " Hz, got " + std::to_string(options.run_sample_rate_hz));
  }
  StateSnapshot& state = publish_.state();
  swap_.publish(state);
  state.module_count = module_count_;
  state.estimate = localization.estimate();
  state.ros_stamp_ns = clock_offset_.to_realtime_ns(state.stamp_s);
  publish_.write();
}

ControlLoop::~ControlLoop() { stop(); }

std::vector<std::string> ControlLoop::start() {
  if (running_.load(std::memory_order_acquire)) {
    throw std::logic_error("ControlLoop::start(): the loop is already running");
  }
  std::vector<std::string> warnings;
  if (options_.realtime) {
    if (auto w = lock_process_memory(); !w.empty()) warnings.push_back(std::move(w));
    if (auto w = dma_latency_.acquire(0); !w.empty()) warnings.push_back(std::move(w));
  }
  stop_requested_.store(false, std::memory_order_release);
  log_.start();
  const auto refresh = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options_.clock_offset_refresh_s));
  clock_thread_ = std::jthread([this, refresh](const std::stop_token& stop) {
    std::unique_lock lock(clock_mutex_);
    while (!clock_wake_.wait_for(lock, stop, refresh, [] { return false; })) {
      if (stop.stop_requested()) return;
      clock_offset_.refresh();
    }
  });
  std::promise<std::string> scheduling;
  auto scheduling_warning = scheduling.get_future();
  running_.store(true, std::memory_order_release);
  try {
    thread_ = std::thread([this, &scheduling] { thread_main(scheduling); });
  } catch (...) {
    running_.store(false, std::memory_order_release);
    clock_thread_ = std::jthread();  // requests its stop and joins
    log_.stop();
    dma_latency_.release();
    throw;
  }
  if (auto w = scheduling_warning.get(); !w.empty()) warnings.push_back(std::move(w));
  return warnings;
}

void ControlLoop::stop() noexcept {
  if (!thread_.joinable()) return;
  stop_requested_.store(true, std::memory_order_release);
  thread_.join();
  clock_thread_.request_stop();
  if (clock_thread_.joinable()) clock_thread_.join();
  log_.stop();
  dma_latency_.release();
  running_.store(false, std::memory_order_release);
}

void ControlLoop::thread_main(std::promise<std::string>& scheduling_warning) noexcept {
  std::string warning;
  try {
    if (options_.realtime) warning = make_thread_fifo(options_.fifo_priority);
  } catch (...) {
    warning = "cannot apply SCHED_FIFO: unexpected error; running SCHED_OTHER";
  }
  prefault_stack();
  scheduling_warning.set_value(std::move(warning));  // start() may return from here on

  std::int64_t deadline_ns = monotonic_ns() + period_ns_;
  while (!stop_requested_.load(std::memory_order_acquire)) {
    sleep_until_ns(deadline_ns);
    const std::int64_t woke_ns = monotonic_ns();
    cycle(static_cast<double>(woke_ns) * 1e-9, false);
    const std::int64_t end_ns = monotonic_ns();
    const std::int64_t next_ns = deadline_ns + period_ns_;
    const bool overrun = end_ns > next_ns;
    timing_.record(woke_ns - deadline_ns, end_ns - woke_ns, overrun);
    deadline_ns = next_ns;
    if (overrun) {
      // Skip the deadlines already missed rather than running a burst of late cycles.
      deadline_ns += ((end_ns - next_ns) / period_ns_ + 1) * period_ns_;
    }
  }
  cycle(monotonic_s(), true);
}

bool ControlLoop::push_motion_capture(const MotionCaptureSample& sample,
                                      MotionCaptureSource source) noexcept {
  return sensors_.push_motion_capture(sample, source);
}

bool ControlLoop::push_gyro(const GyroSample& sample) noexcept {
  return sensors_.push_gyro(sample);
}

Localization* ControlLoop::take_retired_localization(SwapOutcome* outcome) noexcept {
  LoopSwap* retired = swap_.take_retired();
  if (retired == nullptr) return nullptr;
  if (outcome != nullptr) *outcome = retired->outcome;
  return retired->localization;
}

void ControlLoop::request_clear(std::uint64_t id) noexcept {
  LoopRequest request;
  request.kind = LoopRequest::Kind::kClear;
  request.id = id;
  (void)requests_.publish(request);
}

void ControlLoop::request_set_pose(const PoseEstimate& pose, std::uint64_t id) noexcept {
  LoopRequest request;
  request.kind = LoopRequest::Kind::kSetPose;
  request.id = id;
  request.pose = pose;
  (void)requests_.publish(request);
}

bool ControlLoop::pause_hardware(double timeout_s) noexcept {
  hardware_access_.store(HardwareAccess::kPauseRequested, std::memory_order_release);
  const double deadline_s = monotonic_s() + timeout_s;
  for (;;) {
    const HardwareAccess access = hardware_access_.load(std::memory_order_acquire);
    if (access == HardwareAccess::kPaused) return true;
    if (access == HardwareAccess::kPauseRefused) break;
    if (monotonic_s() >= deadline_s) {
      HardwareAccess expected = HardwareAccess::kPauseRequested;
      if (hardware_access_.compare_exchange_strong(expected, HardwareAccess::kCalling,
                                                   std::memory_order_acq_rel)) {
        return false;
      }
      if (expected == HardwareAccess::kPaused) return true;  // granted just now
      break;
    }
    const timespec pause{0, 200000};
    nanosleep(&pause, nullptr);
  }
  hardware_access_.store(HardwareAccess::kCalling, std::memory_order_release);
  return false;
}

void ControlLoop::resume_hardware() noexcept {
  hardware_access_.store(HardwareAccess::kCalling, std::memory_order_release);
}

// A swap at the cycle boundary. One with a new robot model waits for a cycle at rest: a
// drivetrain swapped under a moving robot would change its setpoints mid-motion. At rest,
// no calibration drives the actuators either.
void ControlLoop::take_pending_swap(double now_s) noexcept {
  const bool rest = calibration_.active() == nullptr &&
                    at_rest(publish_.state(), write_.last_write_zero(), module_count_);
  ModelSettings model;
  if (swap_.take(now_s, rest, module_count_, drivetrain_, model, guard_, events_)) {
    apply_model(model);
  }
}

// The new model's limits and encoder resolutions. The robot is at rest: both limiters start
// again from zero, and the twist window from the next reading on.
void ControlLoop::apply_model(const ModelSettings& model) noexcept {
  options_.limits = model.limits;
  options_.wheel_encoder_resolution_rad = model.wheel_encoder_resolution_rad;
  options_.steer_encoder_resolution_rad = model.steer_encoder_resolution_rad;
  command_.set_limits(model.limits);
  odometry_.set_resolutions(model.wheel_encoder_resolution_rad, model.steer_encoder_resolution_rad);
}

void ControlLoop::run_cycle(double now_s) noexcept { cycle(now_s, false); }

// True while the hardware must not be called (pause_hardware()). Grants a pause only to a
// robot in safe stop whose last setpoints were zero; a requester that gave up meanwhile
// wins the exchange and the loop goes on calling the hardware.
bool ControlLoop::hold_hardware() noexcept {
  HardwareAccess access = hardware_access_.load(std::memory_order_acquire);
  if (access == HardwareAccess::kPauseRequested) {
    if (!events_.any_latched()) {
      (void)hardware_access_.compare_exchange_strong(access, HardwareAccess::kPauseRefused,
                                                     std::memory_order_acq_rel);
      return false;
    }
    if (!write_.last_write_zero()) return false;  // still stopping: granted once at rest
    if (hardware_access_.compare_exchange_strong(access, HardwareAccess::kPaused,
                                                 std::memory_order_acq_rel)) {
      access = HardwareAccess::kPaused;
    }
  }
  if (access == HardwareAccess::kPaused) {
    hardware_paused_ = true;
    return true;
  }
  if (hardware_paused_) {
    // The last reading is from before the pause: the next one starts the odometry afresh.
    hardware_paused_ = false;
    read_.forget_previous();
  }
  return false;
}

void ControlLoop::take_request(double now_s, std::uint64_t& clear_id) noexcept {
  LoopRequest request;
  if (!requests_.take(request)) return;
  if (request.kind == LoopRequest::Kind::kClear) {
    clear_id = request.id;  // answered once this cycle's checks have run
    clear_pending_ = true;
    return;
  }
  Localization& localization = *swap_.active();
  LoopReply reply;
  reply.id = request.id;
  const char* thrown = nullptr;
  if (!finite(request.pose.pose)) {
    copy_text("non-finite pose", reply.detail);
  } else if (guard_([&] { return localization.hand_over(request.pose); }, thrown) == Status::kOk) {
    reply.ok = true;
  } else {
    copy_text(thrown != nullptr ? thrown : localization.last_error(), reply.detail);
    if (reply.detail[0] == '\0') copy_text("hand_over failed without a reason", reply.detail);
  }
  if (reply.ok) {
    events_.log(LogLevel::kInfo, LogCode::kPoseSet, now_s, "", static_cast<double>(request.id),
                request.pose.pose.x_m, request.pose.pose.y_m, request.pose.pose.yaw_rad);
  } else {
    events_.log(LogLevel::kWarn, LogCode::kPoseRefused, now_s, "", static_cast<double>(request.id),
                0.0, 0.0, 0.0, reply.detail.data());
  }
  (void)replies_.publish(reply);
}

// Leaves the latched fault (both clear paths).
void ControlLoop::clear_latched_fault(double now_s) noexcept {
  events_.clear_latched(now_s);
  write_.clear_hardware_error();
  command_.drop();  // only a command that arrives from now on moves the robot
}

void ControlLoop::answer_clear(std::uint64_t id, double now_s) noexcept {
  LoopReply reply;
  reply.id = id;
  if (events_.any_latched()) {
    reply.fault = events_.latched();
    reply.detail = events_.latched_detail();
    reply.ok = events_.cycle_fault() == FaultCode::kNone;
    if (reply.ok) {
      clear_latched_fault(now_s);
    } else {
      events_.log(LogLevel::kWarn, LogCode::kClearRefused, now_s, "",
                  static_cast<double>(events_.latched()), static_cast<double>(id), 0.0, 0.0,
                  events_.latched_detail().data());
    }
  } else if (events_.transient() != FaultCode::kNone) {
    reply.fault = events_.transient();
    reply.detail = events_.transient_detail();
    // A missing command stream persists until a command arrives, which resumes by itself.
    reply.ok = events_.transient() != FaultCode::kCommandTimeout;
    if (reply.ok) events_.clear_transient();
  } else {
    reply.ok = true;  // nothing to clear
  }
  (void)replies_.publish(reply);
}

// Leaving safe stop: only on request and only in a cycle without a fault.
void ControlLoop::take_clear(double now_s, std::uint64_t clear_id) noexcept {
  if (clear_requested_.exchange(false, std::memory_order_acq_rel) && events_.any_latched()) {
    if (events_.cycle_fault() == FaultCode::kNone) {
      clear_latched_fault(now_s);
    } else {
      clear_requested_.store(true, std::memory_order_release);
    }
  }
  if (clear_pending_) answer_clear(clear_id, now_s);
}

void ControlLoop::cycle(double now_s, bool final_stop) noexcept {
  events_.begin_cycle(publish_.state().cycle);
  const CycleTime time{now_s, has_last_cycle_, last_cycle_s_};
  if (!final_stop && hold_hardware()) {
    // Paused for a lifecycle call off the loop: no hardware call; the robot is stopped.
    publish_.publish_paused(now_s, clock_offset_.to_realtime_ns(now_s));
    end_cycle(now_s);
    return;
  }

  // Boundary work: the controlled stop, a swap, a calibration, a clear or set-pose request.
  command_.take_stop_request(time, events_);
  take_pending_swap(now_s);
  calibration_.take_pending(now_s, command_.stopping(), command_, events_);
  std::uint64_t clear_id = 0;
  clear_pending_ = false;
  take_request(now_s, clear_id);
  Localization& localization = *swap_.active();

  // Read and check the hardware; odometry and localization.
  const ReadOutcome read = read_.read(now_s, hardware_, sensors_, guard_, events_);
  const HardwareState& current = read_.current();
  if (read.ok && current.motion_capture.valid) {
    publish_.run_samples().note_motion_capture(current.motion_capture);
  }
  const OdometryOutcome odometry = odometry_.update(now_s, read_, read.ok, publish_.state(),
                                                    has_last_cycle_ ? last_cycle_s_ : now_s,
                                                    *drivetrain_, localization, guard_, events_);
  take_clear(now_s, clear_id);

  // Mode and command: the newest velocity command, or a calibration's own setpoints.
  command_.take_command(now_s, events_);
  WriteRequest request;
  const bool had_calibration = calibration_.active() != nullptr;
  request.calibrating =
      calibration_.step(now_s, final_stop || command_.stopping(), current, module_count_,
                        write_.setpoints(), command_, guard_, events_);
  if (request.calibrating) command_.drop();  // velocity commands are ignored meanwhile
  request.calibration_ended = had_calibration && !request.calibrating;
  request.final_stop = final_stop;
  request.moving = command_.moving(request.calibrating || final_stop || events_.any_latched());
  if (request.moving) request.target = command_.command_twist();
  publish_.run_samples().note_command(request.target);

  // Limits -> setpoints -> hardware.
  request.basis = read.ok ? &current : (read_.has_previous() ? &read_.previous() : nullptr);
  const char* hardware_failure = read.failure;  // cause of a hardware fault in this cycle
  const Twist2 applied = write_.write(request, time, *drivetrain_, hardware_, command_, guard_,
                                      events_, hardware_failure);
  odometry_.advance(applied, now_s);
  read_.end_cycle(read.ok);
  // The cycle's boundary: the hardware hears of its failure once, before the next read.
  write_.report_hardware_failure(hardware_failure, now_s, hardware_, guard_, events_);

  // Publish.
  StateSnapshot& state = publish_.state();
  odometry_.publish(odometry, localization, state);
  swap_.publish(state);
  events_.publish(request.calibrating ? LoopMode::kCalibration
                  : request.moving    ? LoopMode::kVelocity
                                      : LoopMode::kIdle,
                  state);
  state.hardware_in_error = write_.hardware_in_error();
  publish_.publish(CycleReport{now_s, clock_offset_.to_realtime_ns(now_s), applied, &current,
                               read.ok, module_count_, command_.stopping()},
                   *drivetrain_, hardware_);
  end_cycle(now_s);
}

}  // namespace swivel::rt
