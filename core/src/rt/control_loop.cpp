// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/control_loop.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <typeinfo>

#include "swivel/rt/exception_text.hpp"

namespace swivel::rt {
namespace {

bool finite(double v) noexcept { return std::isfinite(v); }

bool finite(const Twist2& t) noexcept {
  return finite(t.vx_mps) && finite(t.vy_mps) && finite(t.wz_radps);
}

bool is_zero(const Twist2& t) noexcept {
  return t.vx_mps == 0.0 && t.vy_mps == 0.0 && t.wz_radps == 0.0;
}

bool finite(const Pose2& p) noexcept { return finite(p.x_m) && finite(p.y_m) && finite(p.yaw_rad); }

// The first non-finite field of a reading, as a static cause text; nullptr when all finite.
const char* non_finite_field(const HardwareState& s) noexcept {
  if (!finite(s.stamp_s)) return "non-finite reading timestamp";
  for (std::uint32_t i = 0; i < s.module_count; ++i) {
    if (!finite(s.wheel_angle_rad[i])) return "non-finite wheel angle";
    if (!finite(s.steer_angle_rad[i])) return "non-finite steering angle";
  }
  if (s.gyro_valid && !finite(s.gyro_wz_radps)) return "non-finite gyro rate";
  if (s.motion_capture.valid &&
      (!finite(s.motion_capture.stamp_s) || !finite(s.motion_capture.pose))) {
    return "non-finite motion-capture sample in the reading";
  }
  return nullptr;
}

bool finite(const ActuatorCommand& c) noexcept {
  for (std::uint32_t i = 0; i < c.module_count; ++i) {
    if (!finite(c.wheel_rate_radps[i]) || !finite(c.steer_rate_radps[i])) return false;
  }
  return true;
}

bool finite_covariance(const PoseEstimate& e) noexcept {
  return !e.has_covariance ||
         std::all_of(e.covariance.begin(), e.covariance.end(), [](double v) { return finite(v); });
}

// What is published: a non-finite covariance goes out as none (robot_localization and Nav2
// reject NaN), while the fault says why.
PoseEstimate publishable(PoseEstimate e) noexcept {
  if (!finite_covariance(e)) {
    e.covariance = {};
    e.has_covariance = false;
  }
  return e;
}

bool finite(const MotionCaptureSample& m) noexcept { return finite(m.stamp_s) && finite(m.pose); }

bool all_zero(const ActuatorCommand& c) noexcept {
  for (std::uint32_t i = 0; i < c.module_count && i < kMaxModules; ++i) {
    if (c.wheel_rate_radps[i] != 0.0 || c.steer_rate_radps[i] != 0.0) return false;
  }
  return true;
}

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
      active_localization_(&localization),
      run_samples_(options.run_sample_rate_hz > 0.0 ? 1.0 / options.run_sample_rate_hz : 0.0,
                   1.0 / options.rate_hz),
      timing_(1.0 / options.rate_hz),
      odometry_monitor_(options.odometry_check),
      twist_window_(twist_window_options(options)),
      command_limiter_(options.limits),
      stop_limiter_(stop_limits(options)),
      gyro_watch_(options.external_sensors.gyro),
      motion_capture_watch_(options.external_sensors.motion_capture) {
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
  copy_text(localization_name, state_.localization_plugin);
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
  return motion_capture_.try_push({sample, source});
}

bool ControlLoop::push_gyro(const GyroSample& sample) noexcept { return gyro_.try_push(sample); }

bool ControlLoop::request_swap(LoopSwap* swap) noexcept {
  if (swap == nullptr || swap->localization == nullptr) return false;
  bool idle = false;
  if (!swap_in_flight_.compare_exchange_strong(idle, true, std::memory_order_acq_rel)) {
    return false;
  }
  swap->outcome = SwapOutcome{};
  pending_swap_.store(swap, std::memory_order_release);
  return true;
}

LoopSwap* ControlLoop::take_retired_swap() noexcept {
  LoopSwap* retired = retired_swap_.exchange(nullptr, std::memory_order_acq_rel);
  if (retired != nullptr) swap_in_flight_.store(false, std::memory_order_release);
  return retired;
}

bool ControlLoop::withdraw_swap(LoopSwap* swap) noexcept {
  for (;;) {
    LoopSwap* expected = swap;
    if (pending_swap_.compare_exchange_strong(expected, nullptr, std::memory_order_acq_rel)) {
      swap_in_flight_.store(false, std::memory_order_release);
      return true;
    }
    if (retired_swap_.load(std::memory_order_acquire) == swap ||
        !swap_in_flight_.load(std::memory_order_acquire)) {
      return false;
    }
    // The loop is examining it at this very cycle boundary: it puts it back or retires it.
    const timespec pause{0, 20000};
    nanosleep(&pause, nullptr);
  }
}

bool ControlLoop::request_localization_swap(Localization* next, const char* name) noexcept {
  // The slot is the loop's own; it is free whenever no swap is in flight.
  if (next == nullptr || swap_in_flight_.load(std::memory_order_acquire)) return false;
  localization_only_swap_ = LoopSwap{};
  localization_only_swap_.localization = next;
  copy_text(name, localization_only_swap_.localization_name);
  return request_swap(&localization_only_swap_);
}

Localization* ControlLoop::take_retired_localization(SwapOutcome* outcome) noexcept {
  LoopSwap* retired = take_retired_swap();
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

void ControlLoop::log_event(LogLevel level, LogCode code, double now_s, const char* text, double a,
                            double b, double c, double d, const char* detail) noexcept {
  LogRecord record;
  record.stamp_s = now_s;
  record.cycle = state_.cycle;
  record.level = level;
  record.code = code;
  record.text = text != nullptr ? text : "";
  record.values = {a, b, c, d};
  copy_text(detail, record.detail);
  log_.push(record);
}

void ControlLoop::raise_fault(FaultCode code, double now_s, const char* detail, double value,
                              double limit) noexcept {
  cycle_fault_ = code;
  if (latched_fault_ == code) return;  // the same cause persisting is one event
  latched_fault_ = code;
  // A plugin that gives no reason still leaves a cause to show.
  copy_text(detail != nullptr && detail[0] != '\0' ? detail : fault_code_name(code),
            latched_detail_);
  ++state_.fault_count;
  log_event(LogLevel::kError, LogCode::kFaultRaised, now_s, "safe stop", static_cast<double>(code),
            static_cast<double>(state_.fault_count), value, limit, detail);
}

// A frozen or slipping encoder: the odometry keeps disagreeing with the gyro, or (redundant
// drivetrains) with itself.
void ControlLoop::check_odometry(const OdometryIncrement& odometry, double now_s) noexcept {
  const bool gyro_valid = current_.gyro_valid;
  switch (odometry_monitor_.update(odometry, gyro_valid, current_.gyro_wz_radps)) {
    case OdometryMonitor::Verdict::kConsistent: return;
    case OdometryMonitor::Verdict::kGyroDisagrees:
      raise_fault(FaultCode::kOdometryInconsistent, now_s,
                  "encoder yaw rate disagrees with the gyro",
                  odometry_monitor_.yaw_difference_radps(), odometry_monitor_.gyro_limit_radps());
      return;
    case OdometryMonitor::Verdict::kResidualHigh:
      raise_fault(FaultCode::kOdometryInconsistent, now_s,
                  "drivetrain odometry residual above its limit", odometry_monitor_.residual_mps(),
                  odometry_monitor_.options().residual_limit_mps);
      return;
  }
}

// The newest external gyro sample: at most one ring's worth per cycle, so that a source
// pushing as fast as the loop drains cannot hold the cycle.
void ControlLoop::take_external_gyro(double now_s) noexcept {
  GyroSample sample;
  pop_at_most(gyro_, sample, kGyroDrainLimit, [&](const GyroSample& g) {
    if (finite(g.received_s) && finite(g.wz_radps)) {
      external_gyro_ = g;
      has_external_gyro_ = true;
      gyro_watch_.observe(g.received_s);
    } else {
      log_event(LogLevel::kWarn, LogCode::kMessage, now_s,
                "non-finite external gyro sample dropped", g.received_s, g.wz_radps);
    }
  });
}

// The newest motion-capture sample from outside the hardware (the Swivel topic, the watched
// source), bounded like the gyro's; it fills in when the hardware reading carries none.
void ControlLoop::take_motion_capture(double now_s, bool reading_ok) noexcept {
  MotionCaptureInput input;
  MotionCaptureSample newest;
  pop_at_most(motion_capture_, input, kMotionCaptureDrainLimit, [&](const MotionCaptureInput& in) {
    const MotionCaptureSample& m = in.sample;
    if (!m.valid) return;
    if (finite(m)) {
      newest = m;
      if (in.source == MotionCaptureSource::kWatched) {
        motion_capture_watch_.observe(m.stamp_s);
      }
    } else {
      log_event(LogLevel::kWarn, LogCode::kMotionCaptureRejected, now_s,
                "non-finite motion-capture sample dropped", m.stamp_s);
    }
  });
  if (reading_ok && newest.valid && !current_.motion_capture.valid) {
    current_.motion_capture = newest;
  }
}

// A configured source that went silent is a latched fault; it persists (and refuses a
// clear) for as long as the source stays silent. The causes were written off the loop.
void ControlLoop::check_external_sensors(double now_s) noexcept {
  if (const char* stale = gyro_watch_.check(now_s)) {
    raise_fault(FaultCode::kSensorStale, now_s, stale, gyro_watch_.age_s(now_s),
                gyro_watch_.limit_s());
  }
  if (const char* stale = motion_capture_watch_.check(now_s)) {
    raise_fault(FaultCode::kSensorStale, now_s, stale, motion_capture_watch_.age_s(now_s),
                motion_capture_watch_.limit_s());
  }
}

void ControlLoop::raise_transient_fault(FaultCode code, double now_s, const char* text) noexcept {
  // Every rejected command is its own event; a timeout is one event until a command arrives.
  if (transient_fault_ == code && code == FaultCode::kCommandTimeout) return;
  transient_fault_ = code;
  copy_text(text, transient_detail_);
  ++state_.fault_count;
  log_event(LogLevel::kWarn, LogCode::kFaultRaised, now_s, text, static_cast<double>(code),
            static_cast<double>(state_.fault_count));
}

// Plugins must not throw on the loop; one that does anyway is stopped at this boundary and
// its exception becomes a fault with a controlled stop rather than std::terminate.
// The fault keeps what was thrown ("plugin threw std::runtime_error: <what>"), written into
// thrown_text_ without allocating.
template <class Call>
Status ControlLoop::guarded(Call&& call, const char*& thrown) noexcept {
  thrown = nullptr;
  constexpr std::string_view kPrefix = "plugin threw ";
  copy_text(kPrefix.data(), thrown_text_);
  const std::span<char> rest = std::span(thrown_text_).subspan(kPrefix.size());
  try {
    return call();
  } catch (const std::exception& e) {
    describe_exception(&typeid(e), e.what(), rest);
  } catch (...) {
    describe_exception(current_exception_type(), nullptr, rest);
  }
  thrown = thrown_text_.data();
  return Status::kError;
}

void ControlLoop::write_zero_setpoints() noexcept {
  setpoints_ = ActuatorCommand{};
  setpoints_.module_count = module_count_;
}

// A swap at the cycle boundary. One with a new robot model waits for a cycle at rest: a
// drivetrain swapped under a moving robot would change its setpoints mid-motion.
void ControlLoop::take_pending_swap(double now_s) noexcept {
  LoopSwap* swap = pending_swap_.exchange(nullptr, std::memory_order_acq_rel);
  if (swap == nullptr) return;
  if (swap->drivetrain != nullptr && !at_rest()) {
    pending_swap_.store(swap, std::memory_order_release);  // again next cycle, or withdrawn
    return;
  }
  Localization* outgoing = active_localization_.load(std::memory_order_relaxed);
  Localization* incoming = swap->localization;
  const PoseEstimate handed = outgoing->estimate();
  const char* thrown = nullptr;
  const char* refusal = nullptr;
  if (swap->drivetrain != nullptr && swap->drivetrain->module_count() != module_count_) {
    refusal = "the new drivetrain drives a different number of modules";
  } else if (guarded([&] { return incoming->hand_over(handed); }, thrown) != Status::kOk) {
    refusal = thrown != nullptr ? thrown : incoming->last_error();
    if (refusal == nullptr || refusal[0] == '\0') refusal = "hand_over failed without a reason";
  }
  if (refusal != nullptr) {
    // Roll back: the outgoing instances still hold a valid estimate and stay active; the
    // refused ones go back to the swapping thread. No fault: the robot lost nothing.
    swap->outcome.taken = false;
    copy_text(refusal, swap->outcome.refusal);
    retired_swap_.store(swap, std::memory_order_release);
    log_event(LogLevel::kWarn, LogCode::kLocalizationSwapRefused, now_s, "",
              static_cast<double>(state_.localization_swaps), 0.0, 0.0, 0.0,
              swap->outcome.refusal.data());
    return;
  }
  swap->outcome.taken = true;
  swap->outcome.refusal[0] = '\0';
  active_localization_.store(incoming, std::memory_order_release);
  swap->localization = outgoing;
  state_.localization_plugin = swap->localization_name;
  ++state_.localization_swaps;
  if (swap->drivetrain != nullptr) {
    Drivetrain* replaced = drivetrain_;
    drivetrain_ = swap->drivetrain;
    swap->drivetrain = replaced;
    apply_model(swap->model);
    ++state_.model_swaps;
    log_event(LogLevel::kInfo, LogCode::kMessage, now_s, "robot model swapped at rest",
              static_cast<double>(state_.model_swaps));
  }
  // request_swap() refuses while a swap is in flight, so this slot is empty here.
  retired_swap_.store(swap, std::memory_order_release);
  log_event(LogLevel::kInfo, LogCode::kLocalizationSwapped, now_s, "",
            static_cast<double>(state_.localization_swaps), handed.pose.x_m, handed.pose.y_m,
            handed.pose.yaw_rad, state_.localization_plugin.data());
}

// At rest: the last cycle commanded zero and wrote zero setpoints, no calibration drives
// the actuators, and the encoders measured every wheel and steering rate below
// kAtRestJointRateRadps (no measurement, e.g. after a failed reading, is not at rest).
bool ControlLoop::at_rest() const noexcept {
  if (active_calibration_.load(std::memory_order_relaxed) != nullptr) return false;
  if (!last_write_zero_ || !state_.has_joint_rates) return false;
  const Twist2& command = state_.command_twist;
  if (command.vx_mps != 0.0 || command.vy_mps != 0.0 || command.wz_radps != 0.0) return false;
  for (std::uint32_t i = 0; i < module_count_; ++i) {
    if (!(std::abs(state_.wheel_rate_radps[i]) < kAtRestJointRateRadps) ||
        !(std::abs(state_.steer_rate_radps[i]) < kAtRestJointRateRadps)) {
      return false;
    }
  }
  return true;
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
  if (!twist_window_.set_resolutions(model.wheel_encoder_resolution_rad,
                                     model.steer_encoder_resolution_rad)) {
    (void)twist_window_.set_resolutions(0.0, 0.0);  // unknown: no covariance
  }
  twist_window_.reset();
}

void ControlLoop::take_pending_calibration(double now_s) noexcept {
  if (active_calibration_.load(std::memory_order_relaxed) != nullptr) return;
  Calibration* next = pending_calibration_.exchange(nullptr, std::memory_order_acq_rel);
  if (next == nullptr) return;
  active_calibration_.store(next, std::memory_order_release);
  if (latched_fault_ != FaultCode::kNone || stopping_) {
    // A robot in safe stop must be cleared before anything moves it; one shutting down stays.
    retire_calibration(CalibrationOutcome::kRefused, now_s);
    return;
  }
  has_command_ = false;
  log_event(LogLevel::kInfo, LogCode::kMessage, now_s, "calibration started");
}

void ControlLoop::retire_calibration(CalibrationOutcome outcome, double now_s) noexcept {
  Calibration* outgoing = active_calibration_.load(std::memory_order_relaxed);
  if (outgoing == nullptr) return;
  retired_outcome_.store(outcome, std::memory_order_relaxed);
  // start_calibration() refuses while an instance is in flight, so the slot is empty here.
  retired_calibration_.store(outgoing, std::memory_order_release);
  active_calibration_.store(nullptr, std::memory_order_release);
  has_command_ = false;  // only a command sent after the calibration moves the robot
  log_event(outcome == CalibrationOutcome::kFinished ? LogLevel::kInfo : LogLevel::kWarn,
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
      raise_transient_fault(FaultCode::kCalibrationError, now_s, "calibration cancelled");
    return false;
  }
  if (latched_fault_ != FaultCode::kNone) {
    retire_calibration(CalibrationOutcome::kFailed, now_s);
    return false;
  }
  const char* thrown = nullptr;
  const Status status = guarded([&] { return calibration->step(current_, setpoints_); }, thrown);
  if (status != Status::kOk) {
    raise_fault(FaultCode::kCalibrationError, now_s,
                thrown != nullptr ? thrown : calibration->last_error());
  } else if (setpoints_.module_count != module_count_ || !finite(setpoints_)) {
    raise_fault(FaultCode::kCalibrationError, now_s, "invalid calibration setpoints");
  } else if (calibration->failed()) {
    raise_fault(FaultCode::kCalibrationError, now_s, calibration->last_error());
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
    if (latched_fault_ == FaultCode::kNone) {
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
    has_previous_ = false;
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
  Localization& localization = *active_localization_.load(std::memory_order_relaxed);
  LoopReply reply;
  reply.id = request.id;
  const char* thrown = nullptr;
  if (!finite(request.pose.pose)) {
    copy_text("non-finite pose", reply.detail);
  } else if (guarded([&] { return localization.hand_over(request.pose); }, thrown) == Status::kOk) {
    reply.ok = true;
  } else {
    copy_text(thrown != nullptr ? thrown : localization.last_error(), reply.detail);
    if (reply.detail[0] == '\0') copy_text("hand_over failed without a reason", reply.detail);
  }
  if (reply.ok) {
    log_event(LogLevel::kInfo, LogCode::kPoseSet, now_s, "", static_cast<double>(request.id),
              request.pose.pose.x_m, request.pose.pose.y_m, request.pose.pose.yaw_rad);
  } else {
    log_event(LogLevel::kWarn, LogCode::kPoseRefused, now_s, "", static_cast<double>(request.id),
              0.0, 0.0, 0.0, reply.detail.data());
  }
  (void)replies_.publish(reply);
}

// Leaves the latched fault (both clear paths).
void ControlLoop::clear_latched_fault(double now_s) noexcept {
  log_event(LogLevel::kInfo, LogCode::kFaultCleared, now_s, "",
            static_cast<double>(latched_fault_));
  latched_fault_ = FaultCode::kNone;
  latched_detail_[0] = '\0';
  state_.hardware_in_error = false;
  has_command_ = false;  // only a command that arrives from now on moves the robot
}

void ControlLoop::answer_clear(std::uint64_t id, double now_s) noexcept {
  LoopReply reply;
  reply.id = id;
  if (latched_fault_ != FaultCode::kNone) {
    reply.fault = latched_fault_;
    reply.detail = latched_detail_;
    reply.ok = cycle_fault_ == FaultCode::kNone;
    if (reply.ok) {
      clear_latched_fault(now_s);
    } else {
      log_event(LogLevel::kWarn, LogCode::kClearRefused, now_s, "",
                static_cast<double>(latched_fault_), static_cast<double>(id), 0.0, 0.0,
                latched_detail_.data());
    }
  } else if (transient_fault_ != FaultCode::kNone) {
    reply.fault = transient_fault_;
    reply.detail = transient_detail_;
    // A missing command stream persists until a command arrives, which resumes by itself.
    reply.ok = transient_fault_ != FaultCode::kCommandTimeout;
    if (reply.ok) transient_fault_ = FaultCode::kNone;
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

// Readings resumed after a gap: the localization takes the dead-reckoned pose with the
// covariance widened by what the encoders measured over the gap (`measured`), so that the
// pose does not jump. False when it refuses: it then continues from its own estimate.
bool ControlLoop::end_reading_gap(Localization& localization, const OdometryIncrement& measured,
                                  double now_s) noexcept {
  const PoseEstimate handed = reading_gap_.resume(measured, now_s);
  const char* thrown = nullptr;
  if (guarded([&] { return localization.hand_over(handed); }, thrown) != Status::kOk) {
    log_event(LogLevel::kWarn, LogCode::kMessage, now_s,
              "readings resumed: the localization refused the dead-reckoned pose", 0.0, 0.0, 0.0,
              0.0, thrown != nullptr ? thrown : localization.last_error());
    return false;
  }
  log_event(LogLevel::kInfo, LogCode::kMessage, now_s,
            "readings resumed: pose kept, covariance widened by the gap's error (m, rad)",
            reading_gap_.last_position_error_m(), reading_gap_.last_heading_error_rad());
  return true;
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
  cycle_fault_ = FaultCode::kNone;
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
    log_event(LogLevel::kInfo, LogCode::kMessage, now_s,
              "controlled stop: commands ignored, bringing the robot to rest");
  }
  take_pending_swap(now_s);
  take_pending_calibration(now_s);
  std::uint64_t clear_id = 0;
  clear_pending_ = false;
  take_request(now_s, clear_id);
  Localization& localization = *active_localization_.load(std::memory_order_relaxed);

  // Read and check the hardware.
  bool reading_ok = false;
  const char* hardware_failure = nullptr;  // cause of a hardware fault in this cycle
  const char* thrown = nullptr;
  take_external_gyro(now_s);
  if (guarded([&] { return hardware_.read(now_s, current_); }, thrown) != Status::kOk) {
    hardware_failure = thrown != nullptr ? thrown : hardware_.last_error();
    raise_fault(FaultCode::kHardwareError, now_s, hardware_failure);
  } else if (current_.module_count > kMaxModules) {
    hardware_failure = "module count out of range";
    raise_fault(FaultCode::kHardwareError, now_s, hardware_failure);
  } else {
    if (gyro_watch_.enabled()) {
      // The configured external gyro replaces the hardware's; a stale one is no reading
      // (the localization falls back as on a gyro dropout while the fault stops the robot).
      const bool fresh = has_external_gyro_ && gyro_watch_.fresh(now_s);
      current_.gyro_valid = fresh;
      current_.gyro_wz_radps = fresh ? external_gyro_.wz_radps : 0.0;
    }
    if (const char* field = non_finite_field(current_); field != nullptr) {
      raise_fault(FaultCode::kNonFiniteSensor, now_s, field);
    } else {
      reading_ok = true;
    }
  }
  take_motion_capture(now_s, reading_ok);
  check_external_sensors(now_s);
  if (reading_ok && current_.motion_capture.valid) {
    run_samples_.note_motion_capture(current_.motion_capture);
  }
  if (!reading_ok && has_previous_ && !reading_gap_.active()) {
    // Readings stopped: the odometry follows the controlled stop until they resume.
    reading_gap_.begin(state_.estimate, state_.odometry_twist,
                       state_.has_twist_covariance ? &state_.twist_covariance : nullptr,
                       has_last_cycle_ ? last_cycle_s_ : now_s);
  }
  const bool resuming = reading_ok && reading_gap_.active();

  // Odometry and localization. The twist window goes first: its forward kinematics calls
  // leave the drivetrain's module states to the cycle's own call.
  OdometryIncrement odometry;
  bool twist_ok = false;
  if (reading_ok) {
    if (!has_previous_ || resuming) twist_window_.reset();  // no fit across missing readings
    twist_window_.push(current_);
  }
  if (reading_ok && has_previous_) {
    // A refusal here is no fault: the cycle's own forward() below decides that.
    twist_ok = guarded([&] { return twist_window_.estimate(*drivetrain_, twist_estimate_); },
                       thrown) == Status::kOk;
    if (guarded([&] { return drivetrain_->forward(previous_, current_, odometry); }, thrown) !=
        Status::kOk) {
      raise_fault(FaultCode::kDrivetrainError, now_s,
                  thrown != nullptr ? thrown : drivetrain_->last_error());
      // An encoder jump must not stay in the window once the fault is cleared.
      twist_window_.reset();
      twist_ok = false;
    } else if (resuming && end_reading_gap(localization, odometry, now_s)) {
      // The motion over the gap went into the handed-over covariance, not into the pose.
    } else if (guarded([&] { return localization.update(odometry, current_); }, thrown) !=
               Status::kOk) {
      raise_fault(FaultCode::kLocalizationError, now_s,
                  thrown != nullptr ? thrown : localization.last_error());
    } else if (!finite(localization.estimate().pose)) {
      raise_fault(FaultCode::kLocalizationError, now_s, "non-finite pose estimate");
    } else if (!finite_covariance(localization.estimate())) {
      raise_fault(FaultCode::kLocalizationError, now_s, "non-finite pose covariance");
    }
    if (odometry.valid) check_odometry(odometry, now_s);
  }
  if (resuming && reading_gap_.active()) {
    // Nothing measured over the gap (the hardware was paused, or the drivetrain refused the
    // increment): the dead-reckoned pose is all there is.
    (void)end_reading_gap(localization, OdometryIncrement{}, now_s);
  }

  // Leaving safe stop: only on request and only in a cycle without a fault.
  if (clear_requested_.exchange(false, std::memory_order_acq_rel)) {
    if (latched_fault_ != FaultCode::kNone) {
      if (cycle_fault_ == FaultCode::kNone) {
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
      transient_fault_ = FaultCode::kNone;
    } else {
      has_command_ = false;
      raise_transient_fault(FaultCode::kNonFiniteCommand, now_s, "non-finite command rejected");
      log_event(LogLevel::kWarn, LogCode::kCommandRejected, now_s, "non-finite velocity command",
                static_cast<double>(incoming.sequence));
    }
  }
  if (stopping_) has_command_ = false;  // shutting down: no command moves the robot again
  if (has_command_ && now_s - command_.received_s > options_.command_timeout_s) {
    has_command_ = false;
    // A stream whose last word was a stop (Nav2 after every goal, a teleop released) has
    // simply ended: the robot is idle, not faulty. Only one that went silent mid-motion is.
    if (!is_zero(command_.twist)) {
      raise_transient_fault(FaultCode::kCommandTimeout, now_s, "velocity command timed out");
    }
  }

  // Command -> limits -> setpoints -> hardware. A calibration writes module setpoints itself.
  const bool had_calibration = active_calibration_.load(std::memory_order_relaxed) != nullptr;
  const bool calibrating = step_calibration(now_s, final_stop || stopping_);
  if (calibrating) has_command_ = false;  // velocity commands are ignored meanwhile
  Twist2 target;
  const bool moving = !calibrating && !final_stop && !stopping_ &&
                      latched_fault_ == FaultCode::kNone && has_command_;
  if (moving) target = command_.twist;
  run_samples_.note_command(target);
  Twist2 applied;
  const HardwareState* basis = reading_ok ? &current_ : (has_previous_ ? &previous_ : nullptr);
  bool zeroed = basis == nullptr && !calibrating;
  if (had_calibration && !calibrating) {
    // The calibration ended this cycle: stop at once rather than through the drivetrain,
    // whose state lags behind the procedure's setpoints.
    write_zero_setpoints();
  } else if (basis != nullptr && !calibrating) {
    // The final cycle stops at once: the daemon brings the robot to rest before it.
    const Twist2 limited = final_stop ? Twist2{} : limit(target, !moving, now_s);
    if (guarded(
            [&] { return drivetrain_->inverse(limited, *basis, period_s_, setpoints_, applied); },
            thrown) != Status::kOk) {
      raise_fault(FaultCode::kDrivetrainError, now_s,
                  thrown != nullptr ? thrown : drivetrain_->last_error());
      zeroed = true;
    } else if (!finite(setpoints_) || !finite(applied)) {
      raise_fault(FaultCode::kDrivetrainError, now_s, "non-finite setpoints");
      zeroed = true;
    } else {
      follow_drivetrain(limited, applied);
    }
  }
  if (zeroed) {
    write_zero_setpoints();
    applied = Twist2{};
    if (basis != nullptr) {
      log_event(LogLevel::kWarn, LogCode::kZeroSetpointFallback, now_s,
                "inverse kinematics failed: zero setpoints written");
    }
  }
  if (calibrating || zeroed || final_stop || (had_calibration && !calibrating)) {
    limiter_->reset(applied);  // the limits start again from what the robot was given
  }
  if (guarded([&] { return hardware_.write(setpoints_); }, thrown) != Status::kOk) {
    hardware_failure = thrown != nullptr ? thrown : hardware_.last_error();
    raise_fault(FaultCode::kHardwareError, now_s, hardware_failure);
  } else {
    last_write_zero_ = all_zero(setpoints_);
  }
  if (reading_gap_.active()) reading_gap_.advance(applied, now_s);
  if (reading_ok) {
    previous_ = current_;
    has_previous_ = true;
  }
  // The cycle's boundary: the hardware hears of its failure once, before the next read.
  if (hardware_failure != nullptr && !state_.hardware_in_error) {
    state_.hardware_in_error = true;
    (void)guarded(
        [&] {
          hardware_.on_error(hardware_failure);
          return Status::kOk;
        },
        thrown);
    log_event(LogLevel::kWarn, LogCode::kMessage, now_s, "hardware error state: on_error() called",
              0.0, 0.0, 0.0, 0.0, hardware_failure);
  }

  // Publish.
  ++state_.cycle;
  state_.stamp_s = now_s;
  state_.ros_stamp_ns = clock_offset_.to_realtime_ns(now_s);
  state_.estimate =
      reading_gap_.active() ? reading_gap_.estimate() : publishable(localization.estimate());
  if (twist_ok) {
    state_.odometry_twist = twist_estimate_.twist;
    state_.twist_covariance = twist_estimate_.covariance;
    state_.has_twist_covariance = twist_estimate_.has_covariance;
    state_.wheel_rate_radps = twist_estimate_.wheel_rate_radps;
    state_.steer_rate_radps = twist_estimate_.steer_rate_radps;
    state_.has_joint_rates = true;
    reading_gap_.forget_twist();
  } else if (reading_gap_.has_twist()) {
    state_.odometry_twist = reading_gap_.twist();
    state_.twist_covariance = reading_gap_.twist_covariance();
    state_.has_twist_covariance = reading_gap_.has_twist_covariance();
    state_.has_joint_rates = false;
  } else {
    state_.odometry_twist = odometry.valid ? odometry.twist : Twist2{};
    state_.twist_covariance = {};
    state_.has_twist_covariance = false;
    state_.has_joint_rates = false;
  }
  state_.odometry_residual = odometry.valid ? odometry.residual : 0.0;
  state_.command_twist = applied;
  state_.gyro_wz_radps = reading_ok && current_.gyro_valid ? current_.gyro_wz_radps : 0.0;
  state_.module_count = module_count_;
  drivetrain_->module_states(std::span<ModuleState>(state_.modules.data(), module_count_));
  if (latched_fault_ != FaultCode::kNone) {
    state_.mode = LoopMode::kSafeStop;
    state_.fault = latched_fault_;
    state_.fault_detail = latched_detail_;
  } else {
    state_.mode = calibrating ? LoopMode::kCalibration
                  : moving    ? LoopMode::kVelocity
                              : LoopMode::kIdle;
    state_.fault = transient_fault_;
    if (transient_fault_ == FaultCode::kNone) {
      state_.fault_detail[0] = '\0';
    } else {
      state_.fault_detail = transient_detail_;
    }
  }
  state_.has_truth = hardware_.ground_truth(state_.truth);
  state_.wheel_angle_rad = current_.wheel_angle_rad;
  state_.steer_angle_rad = current_.steer_angle_rad;
  state_.stopping = stopping_;
  snapshot_.write(state_);
  run_samples_.publish(state_, now_s);
  last_cycle_s_ = now_s;
  has_last_cycle_ = true;
}

}  // namespace swivel::rt
