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

// The controlled stop: the model's limits, with the stop's deceleration on the axes whose
// model has no acceleration limit.
MotionLimits stop_limits(const LoopOptions& options) {
  MotionLimits limits = options.limits;
  if (!limits.linear_acceleration_mps2) {
    limits.linear_acceleration_mps2 = options.stop_linear_deceleration_mps2;
  }
  if (!limits.angular_acceleration_radps2) {
    limits.angular_acceleration_radps2 = options.stop_angular_deceleration_radps2;
  }
  return limits;
}

// Below these a drivetrain may fade a small twist out on purpose (swpc near standstill).
constexpr double kFollowFloorMps = 0.02;
constexpr double kFollowFloorRadps = 0.02;

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
      swap_(localization, localization_name),
      run_samples_(options.run_sample_rate_hz > 0.0 ? 1.0 / options.run_sample_rate_hz : 0.0,
                   1.0 / options.rate_hz),
      timing_(1.0 / options.rate_hz),
      odometry_(options.odometry_check, twist_window_options(options)),
      command_limiter_(options.limits),
      stop_limiter_(stop_limits(options)),
      sensors_(options.external_sensors) {
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
  swap_.publish(state_);
  state_.module_count = module_count_;
  state_.estimate = localization.estimate();
  state_.ros_stamp_ns = clock_offset_.to_realtime_ns(state_.stamp_s);
  snapshot_.write(state_);
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

bool ControlLoop::push_command(const VelocityCommand& command) noexcept {
  (void)commands_.publish(command);
  return true;
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

void ControlLoop::request_controlled_stop(double requested_s) noexcept {
  bool expected = false;
  if (controlled_stop_requested_.load(std::memory_order_acquire)) return;
  controlled_stop_requested_s_.store(requested_s, std::memory_order_relaxed);
  (void)controlled_stop_requested_.compare_exchange_strong(expected, true,
                                                           std::memory_order_acq_rel);
}

void ControlLoop::resume_hardware() noexcept {
  hardware_access_.store(HardwareAccess::kCalling, std::memory_order_release);
}

bool ControlLoop::start_calibration(Calibration* calibration) noexcept {
  if (calibration == nullptr) return false;
  if (calibration_in_flight_.load(std::memory_order_acquire)) return false;
  calibration_in_flight_.store(true, std::memory_order_release);
  cancel_calibration_.store(false, std::memory_order_release);
  pending_calibration_.store(calibration, std::memory_order_release);
  return true;
}

void ControlLoop::cancel_calibration() noexcept {
  if (!calibration_in_flight_.load(std::memory_order_acquire)) return;
  // Not taken by the loop yet: hand it back directly. At most one instance is in flight,
  // so the retire slot is empty and the loop will never see this one.
  if (Calibration* pending = pending_calibration_.exchange(nullptr, std::memory_order_acq_rel)) {
    retired_outcome_.store(CalibrationOutcome::kCancelled, std::memory_order_relaxed);
    retired_calibration_.store(pending, std::memory_order_release);
    return;
  }
  cancel_calibration_.store(true, std::memory_order_release);
}

Calibration* ControlLoop::take_finished_calibration(CalibrationOutcome* outcome) noexcept {
  Calibration* retired = retired_calibration_.exchange(nullptr, std::memory_order_acq_rel);
  if (retired == nullptr) return nullptr;
  if (outcome != nullptr) *outcome = retired_outcome_.load(std::memory_order_relaxed);
  cancel_calibration_.store(false, std::memory_order_release);
  calibration_in_flight_.store(false, std::memory_order_release);
  return retired;
}

void ControlLoop::write_zero_setpoints() noexcept {
  setpoints_ = ActuatorCommand{};
  setpoints_.module_count = module_count_;
}

// A swap at the cycle boundary. One with a new robot model waits for a cycle at rest: a
// drivetrain swapped under a moving robot would change its setpoints mid-motion. At rest,
// no calibration drives the actuators either.
void ControlLoop::take_pending_swap(double now_s) noexcept {
  const bool rest = active_calibration_.load(std::memory_order_relaxed) == nullptr &&
                    at_rest(state_, last_write_zero_, module_count_);
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
  command_limiter_ = motion::TwistLimiter(options_.limits);
  stop_limiter_ = motion::TwistLimiter(stop_limits(options_));
  command_limiter_.reset();
  stop_limiter_.reset();
  limiter_ = &stop_limiter_;
  odometry_.set_resolutions(model.wheel_encoder_resolution_rad, model.steer_encoder_resolution_rad);
}

void ControlLoop::take_pending_calibration(double now_s) noexcept {
  if (active_calibration_.load(std::memory_order_relaxed) != nullptr) return;
  Calibration* next = pending_calibration_.exchange(nullptr, std::memory_order_acq_rel);
  if (next == nullptr) return;
  active_calibration_.store(next, std::memory_order_release);
  if (events_.any_latched() || stopping_) {
    // A robot in safe stop must be cleared before anything moves it; one shutting down stays.
    retire_calibration(CalibrationOutcome::kRefused, now_s);
    return;
  }
  has_command_ = false;
  events_.log(LogLevel::kInfo, LogCode::kMessage, now_s, "calibration started");
}

void ControlLoop::retire_calibration(CalibrationOutcome outcome, double now_s) noexcept {
  Calibration* outgoing = active_calibration_.load(std::memory_order_relaxed);
  if (outgoing == nullptr) return;
  retired_outcome_.store(outcome, std::memory_order_relaxed);
  // start_calibration() refuses while an instance is in flight, so the slot is empty here.
  retired_calibration_.store(outgoing, std::memory_order_release);
  active_calibration_.store(nullptr, std::memory_order_release);
  has_command_ = false;  // only a command sent after the calibration moves the robot
  events_.log(outcome == CalibrationOutcome::kFinished ? LogLevel::kInfo : LogLevel::kWarn,
              LogCode::kMessage, now_s,
              outcome == CalibrationOutcome::kFinished    ? "calibration finished"
              : outcome == CalibrationOutcome::kCancelled ? "calibration cancelled"
              : outcome == CalibrationOutcome::kRefused
                  ? "calibration refused: fault latched or stopping"
                  : "calibration stopped by a fault");
}

// One cycle of an active calibration. Returns true while it drives the actuators this cycle
// (setpoints_ filled); false when there is none or it ended this cycle (the caller writes
// zero setpoints).
bool ControlLoop::step_calibration(double now_s, bool final_stop) noexcept {
  Calibration* calibration = active_calibration_.load(std::memory_order_relaxed);
  if (calibration == nullptr) return false;
  if (final_stop || cancel_calibration_.exchange(false, std::memory_order_acq_rel)) {
    retire_calibration(CalibrationOutcome::kCancelled, now_s);
    if (!final_stop)
      events_.raise_transient(FaultCode::kCalibrationError, now_s, "calibration cancelled");
    return false;
  }
  if (events_.any_latched()) {
    retire_calibration(CalibrationOutcome::kFailed, now_s);
    return false;
  }
  const char* thrown = nullptr;
  const Status status =
      guard_([&] { return calibration->step(read_.current(), setpoints_); }, thrown);
  if (status != Status::kOk) {
    events_.raise(FaultCode::kCalibrationError, now_s,
                  thrown != nullptr ? thrown : calibration->last_error());
  } else if (setpoints_.module_count != module_count_ || !finite(setpoints_)) {
    events_.raise(FaultCode::kCalibrationError, now_s, "invalid calibration setpoints");
  } else if (calibration->failed()) {
    events_.raise(FaultCode::kCalibrationError, now_s, calibration->last_error());
  } else if (calibration->finished()) {
    retire_calibration(CalibrationOutcome::kFinished, now_s);
    return false;
  } else {
    return true;
  }
  retire_calibration(CalibrationOutcome::kFailed, now_s);
  return false;
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
    if (!last_write_zero_) return false;  // still stopping: granted once at rest
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
  state_.hardware_in_error = false;
  has_command_ = false;  // only a command that arrives from now on moves the robot
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

Twist2 ControlLoop::limit(const Twist2& target, bool stopping, double now_s) noexcept {
  motion::TwistLimiter& limiter = stopping ? stop_limiter_ : command_limiter_;
  if (&limiter != limiter_) {
    limiter.continue_from(*limiter_);
    limiter_ = &limiter;
  }
  if (!limiter.active()) {
    limiter.reset(target);
    return target;
  }
  // The time that really passed, so that a late cycle does not stretch a stop. Towards a
  // command it is bounded, so that a stalled loop does not make the twist jump up; a stop
  // only ever moves towards zero, so it takes all of it.
  double dt_s = period_s_;
  if (has_last_cycle_ && now_s > last_cycle_s_) {
    dt_s = stopping ? now_s - last_cycle_s_ : std::min(now_s - last_cycle_s_, 10.0 * period_s_);
  }
  if (stopping && stop_catch_up_s_ != 0.0) {
    dt_s = std::max(dt_s + stop_catch_up_s_, 0.0);
    stop_catch_up_s_ = 0.0;
  }
  return limiter.step(target, dt_s);
}

// The drivetrain scaled the twist down to its own wheel or steering limits: the limiter
// continues from what the robot was commanded, so that a later stop ramps down from the
// robot's speed and not from one it never reached. Below the floors a drivetrain may fade a
// small twist out on purpose; following it there would keep the robot from ever starting.
void ControlLoop::follow_drivetrain(const Twist2& limited, const Twist2& applied) noexcept {
  const auto follow = [](motion::AxisLimiter& axis, double wanted, double got, double floor) {
    if (std::abs(wanted) >= floor && std::abs(got) < std::abs(wanted) * (1.0 - 1e-9)) {
      axis.reset(got);
    }
  };
  follow(limiter_->x(), limited.vx_mps, applied.vx_mps, kFollowFloorMps);
  follow(limiter_->y(), limited.vy_mps, applied.vy_mps, kFollowFloorMps);
  follow(limiter_->wz(), limited.wz_radps, applied.wz_radps, kFollowFloorRadps);
}

void ControlLoop::cycle(double now_s, bool final_stop) noexcept {
  events_.begin_cycle(state_.cycle);
  if (!final_stop && hold_hardware()) {
    // Paused for a lifecycle call off the loop: no hardware call; the robot is stopped.
    ++state_.cycle;
    state_.stamp_s = now_s;
    state_.ros_stamp_ns = clock_offset_.to_realtime_ns(now_s);
    state_.odometry_twist = Twist2{};
    state_.has_twist_covariance = false;
    state_.twist_covariance = {};
    state_.has_joint_rates = false;
    state_.command_twist = Twist2{};
    snapshot_.write(state_);
    last_cycle_s_ = now_s;
    has_last_cycle_ = true;
    return;
  }
  if (!stopping_ && controlled_stop_requested_.load(std::memory_order_acquire)) {
    stopping_ = true;
    // The setpoint about to be written holds for a period, and the last one has held since
    // the request: the first step decelerates for both, so that the stop brakes as if it had
    // begun at the request and each setpoint were the ramp's value mid-period.
    const double since_request_s =
        now_s - controlled_stop_requested_s_.load(std::memory_order_relaxed);
    stop_catch_up_s_ = std::max(since_request_s, 0.0) + 0.5 * period_s_ -
                       (has_last_cycle_ ? std::max(now_s - last_cycle_s_, 0.0) : period_s_);
    events_.log(LogLevel::kInfo, LogCode::kMessage, now_s,
                "controlled stop: commands ignored, bringing the robot to rest");
  }
  take_pending_swap(now_s);
  take_pending_calibration(now_s);
  std::uint64_t clear_id = 0;
  clear_pending_ = false;
  take_request(now_s, clear_id);
  Localization& localization = *swap_.active();

  // Read and check the hardware.
  const ReadOutcome read = read_.read(now_s, hardware_, sensors_, guard_, events_);
  const bool reading_ok = read.ok;
  const char* hardware_failure = read.failure;  // cause of a hardware fault in this cycle
  const char* thrown = nullptr;
  const HardwareState& current = read_.current();
  const HardwareState& previous = read_.previous();
  const bool has_previous = read_.has_previous();
  if (reading_ok && current.motion_capture.valid) {
    run_samples_.note_motion_capture(current.motion_capture);
  }

  // Odometry and localization.
  const OdometryOutcome odometry =
      odometry_.update(now_s, read_, reading_ok, state_, has_last_cycle_ ? last_cycle_s_ : now_s,
                       *drivetrain_, localization, guard_, events_);

  // Leaving safe stop: only on request and only in a cycle without a fault.
  if (clear_requested_.exchange(false, std::memory_order_acq_rel)) {
    if (events_.any_latched()) {
      if (events_.cycle_fault() == FaultCode::kNone) {
        clear_latched_fault(now_s);
      } else {
        clear_requested_.store(true, std::memory_order_release);
      }
    }
  }
  if (clear_pending_) answer_clear(clear_id, now_s);

  // Newest velocity command (one per cycle at most: the slot keeps only the newest).
  VelocityCommand incoming;
  if (commands_.take(incoming) && !stopping_) {
    if (finite(incoming.twist) && finite(incoming.received_s)) {
      command_ = incoming;
      has_command_ = true;
      events_.clear_transient();
    } else {
      has_command_ = false;
      events_.raise_transient(FaultCode::kNonFiniteCommand, now_s, "non-finite command rejected");
      events_.log(LogLevel::kWarn, LogCode::kCommandRejected, now_s, "non-finite velocity command",
                  static_cast<double>(incoming.sequence));
    }
  }
  if (stopping_) has_command_ = false;  // shutting down: no command moves the robot again
  if (has_command_ && now_s - command_.received_s > options_.command_timeout_s) {
    has_command_ = false;
    // A stream whose last word was a stop (Nav2 after every goal, a teleop released) has
    // simply ended: the robot is idle, not faulty. Only one that went silent mid-motion is.
    if (!is_zero(command_.twist)) {
      events_.raise_transient(FaultCode::kCommandTimeout, now_s, "velocity command timed out");
    }
  }

  // Command -> limits -> setpoints -> hardware. A calibration writes module setpoints itself.
  const bool had_calibration = active_calibration_.load(std::memory_order_relaxed) != nullptr;
  const bool calibrating = step_calibration(now_s, final_stop || stopping_);
  if (calibrating) has_command_ = false;  // velocity commands are ignored meanwhile
  Twist2 target;
  const bool moving =
      !calibrating && !final_stop && !stopping_ && !events_.any_latched() && has_command_;
  if (moving) target = command_.twist;
  run_samples_.note_command(target);
  Twist2 applied;
  const HardwareState* basis = reading_ok ? &current : (has_previous ? &previous : nullptr);
  bool zeroed = basis == nullptr && !calibrating;
  if (had_calibration && !calibrating) {
    // The calibration ended this cycle: stop at once rather than through the drivetrain,
    // whose state lags behind the procedure's setpoints.
    write_zero_setpoints();
  } else if (basis != nullptr && !calibrating) {
    // The final cycle stops at once: the daemon brings the robot to rest before it.
    const Twist2 limited = final_stop ? Twist2{} : limit(target, !moving, now_s);
    if (guard_(
            [&] { return drivetrain_->inverse(limited, *basis, period_s_, setpoints_, applied); },
            thrown) != Status::kOk) {
      events_.raise(FaultCode::kDrivetrainError, now_s,
                    thrown != nullptr ? thrown : drivetrain_->last_error());
      zeroed = true;
    } else if (!finite(setpoints_) || !finite(applied)) {
      events_.raise(FaultCode::kDrivetrainError, now_s, "non-finite setpoints");
      zeroed = true;
    } else {
      follow_drivetrain(limited, applied);
    }
  }
  if (zeroed) {
    write_zero_setpoints();
    applied = Twist2{};
    if (basis != nullptr) {
      events_.log(LogLevel::kWarn, LogCode::kZeroSetpointFallback, now_s,
                  "inverse kinematics failed: zero setpoints written");
    }
  }
  if (calibrating || zeroed || final_stop || (had_calibration && !calibrating)) {
    limiter_->reset(applied);  // the limits start again from what the robot was given
  }
  if (guard_([&] { return hardware_.write(setpoints_); }, thrown) != Status::kOk) {
    hardware_failure = thrown != nullptr ? thrown : hardware_.last_error();
    events_.raise(FaultCode::kHardwareError, now_s, hardware_failure);
  } else {
    last_write_zero_ = all_zero(setpoints_);
  }
  odometry_.advance(applied, now_s);
  read_.end_cycle(reading_ok);
  // The cycle's boundary: the hardware hears of its failure once, before the next read.
  if (hardware_failure != nullptr && !state_.hardware_in_error) {
    state_.hardware_in_error = true;
    (void)guard_(
        [&] {
          hardware_.on_error(hardware_failure);
          return Status::kOk;
        },
        thrown);
    events_.log(LogLevel::kWarn, LogCode::kMessage, now_s,
                "hardware error state: on_error() called", 0.0, 0.0, 0.0, 0.0, hardware_failure);
  }

  // Publish.
  ++state_.cycle;
  state_.stamp_s = now_s;
  state_.ros_stamp_ns = clock_offset_.to_realtime_ns(now_s);
  odometry_.publish(odometry, localization, state_);
  swap_.publish(state_);
  state_.command_twist = applied;
  state_.gyro_wz_radps = reading_ok && current.gyro_valid ? current.gyro_wz_radps : 0.0;
  state_.module_count = module_count_;
  drivetrain_->module_states(std::span<ModuleState>(state_.modules.data(), module_count_));
  events_.publish(calibrating ? LoopMode::kCalibration
                  : moving    ? LoopMode::kVelocity
                              : LoopMode::kIdle,
                  state_);
  state_.has_truth = hardware_.ground_truth(state_.truth);
  state_.wheel_angle_rad = current.wheel_angle_rad;
  state_.steer_angle_rad = current.steer_angle_rad;
  state_.stopping = stopping_;
  snapshot_.write(state_);
  run_samples_.publish(state_, now_s);
  last_cycle_s_ = now_s;
  has_last_cycle_ = true;
}

}  // namespace swivel::rt
