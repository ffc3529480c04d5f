// SPDX-License-Identifier: Apache-2.0
#pragma once
// The real-time loop (docs/architecture.md "One cycle of the loop"). One thread at a fixed period
// runs: hot swap (if requested) -> read hardware -> reject non-finite readings -> drivetrain
// forward -> localization update -> newest velocity command -> motion limits -> drivetrain
// inverse -> write hardware -> publish a StateSnapshot -> record timing. cycle() only orders
// the steps: each is a stage of its own type and file (swivel/rt/*_stage.hpp), with its tests:
// SwapStage and CalibrationStage at the cycle boundary, HardwareReadStage with
// ExternalSensorStage, OdometryStage, CommandStage (mode and command limits), WriteStage and
// PublishStage (snapshot and run samples). They share LoopEvents (faults and log records) and
// PluginGuard (the boundary around every plugin call).
//
// Motion limits: every velocity command goes through a motion::TwistLimiter with the robot
// model's `limits:` (LoopOptions::limits). Whenever the loop itself stops the robot (a
// fault, a command timeout, no command, the controlled stop before shutdown) the twist is
// brought to zero by a second limiter: the same limits, with LoopOptions' stop deceleration
// on the axes whose model has no acceleration limit. The loop's final cycle (stop()) writes
// zero setpoints at once.
//
// Faults stop the robot in a controlled way (the limited twist through inverse kinematics)
// and the loop keeps running:
//  - a non-finite reading, a plugin returning kError (or a non-finite pose), or odometry that
//    keeps disagreeing with the gyro or with itself (OdometryMonitor): mode
//    kSafeStop with the fault latched until a clear is requested (clear_fault() waits for a
//    clean cycle; request_clear() is answered at the next cycle, refused while the cause
//    persists); the velocity command seen before is then discarded so that only a fresh one
//    moves the robot again;
//  - the newest velocity command older than command_timeout_s: mode kIdle, with fault
//    kCommandTimeout only when that command asked for motion (a stream whose last command
//    was zero has ended normally: idle without a fault); a fresh valid command resumes;
//  - a non-finite velocity command: rejected, mode kIdle with fault kNonFiniteCommand; a
//    fresh valid command resumes;
//  - a configured external source (LoopOptions::external_sensors: a DDS gyro, a DDS
//    motion-capture topic) whose newest sample is older than its max age, or that sent
//    nothing within its start-up grace: mode kSafeStop with fault kSensorStale, latched
//    like the first kind (a clear is refused while the source stays silent).
// Each fault event (not each faulty cycle) is counted and logged through RtLog; the snapshot
// carries the active fault's code and its cause (StateSnapshot::fault_detail). A hardware
// fault also calls Hardware::on_error() at the end of its cycle (once, until a clear).
//
// Hot swap (request_swap()): the incoming localization's hand_over() decides. kOk: it becomes
// active and the outgoing one is retired. kError or an exception: the outgoing one stays
// active, the incoming one is retired instead and the refusal comes back with it; no fault
// latches. A swap that carries a new robot model (a drivetrain configured for it and the
// model's limits and encoder resolutions) is taken only at a cycle boundary where the robot
// is at rest (at_rest()): until then it waits, and the requester may withdraw it; the new
// drivetrain and localization are taken together or not at all.
//
// Calibration: start_calibration() hands the loop a configured Calibration; from the next
// cycle boundary the mode is kCalibration and the setpoints come from its step() (the
// drivetrain's inverse kinematics is bypassed; velocity commands are ignored). It ends with
// zero setpoints in the same cycle when the procedure finishes (mode kIdle), is cancelled
// (mode kIdle, fault kCalibrationError until a fresh command), fails (kSafeStop with
// kCalibrationError) or any other fault stops the robot (kSafeStop with that fault). The
// instance then waits in a retire slot for take_finished_calibration(). Only a command that
// arrives after the calibration moves the robot again.
//
// Threads: the loop thread (or the caller of run_cycle()) runs every plugin call. One
// command-source thread may call push_command() (velocity commands go through a latest-value
// slot: the newest command wins), one external-sensor thread (the DDS subscriber)
// push_motion_capture() and push_gyro(), one thread (the configuration watcher) the swap
// pair, one thread (the calibration runner) the calibration calls, one thread (the daemon's
// request handler) request_clear(), request_set_pose(), take_reply() and the hardware pause
// pair; any thread may call latest(), timing(), clear_fault(), request_controlled_stop(),
// running() and now_s().

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <future>
#include <limits>
#include <mutex>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "swivel/motion/twist_limiter.hpp"
#include "swivel/plugin/calibration.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/rt/calibration_stage.hpp"
#include "swivel/rt/clock_offset.hpp"
#include "swivel/rt/command_stage.hpp"
#include "swivel/rt/external_sensor_stage.hpp"
#include "swivel/rt/hardware_read_stage.hpp"
#include "swivel/rt/latest_value.hpp"
#include "swivel/rt/loop_events.hpp"
#include "swivel/rt/odometry_stage.hpp"
#include "swivel/rt/plugin_guard.hpp"
#include "swivel/rt/publish_stage.hpp"
#include "swivel/rt/realtime.hpp"
#include "swivel/rt/rt_log.hpp"
#include "swivel/rt/run_sample.hpp"
#include "swivel/rt/run_sample_stage.hpp"
#include "swivel/rt/state_snapshot.hpp"
#include "swivel/rt/swap_stage.hpp"
#include "swivel/rt/timing_stats.hpp"
#include "swivel/rt/twist_window.hpp"
#include "swivel/rt/write_stage.hpp"

namespace swivel::rt {

struct LoopOptions {
  double rate_hz = 1000.0;
  int fifo_priority = 80;          ///< SCHED_FIFO priority where permitted
  bool realtime = true;            ///< try SCHED_FIFO, mlockall and /dev/cpu_dma_latency
  double command_timeout_s = 0.5;  ///< older velocity commands stop the robot
  /// Encoders against the gyro and the drivetrain residual (docs/faults.md).
  OdometryCheckOptions odometry_check;
  /// The robot model's `limits:` (velocity, acceleration and jerk per axis): applied to every
  /// velocity command and to the controlled stop. Absent limits are not applied.
  MotionLimits limits;
  /// Deceleration of the controlled stop on the axes whose `limits` has no acceleration
  /// limit: x and y, m/s^2, and yaw, rad/s^2. Infinite: zero at once on those axes. The
  /// daemon sets them from swiveld.yaml `controlled_stop:`.
  double stop_linear_deceleration_mps2 = std::numeric_limits<double>::infinity();
  double stop_angular_deceleration_radps2 = std::numeric_limits<double>::infinity();
  /// The published twist (StateSnapshot::odometry_twist) is fitted over the readings of the
  /// last twist_window_s (N = twist_window_s * rate_hz + 1 readings, at most
  /// kMaxTwistWindowReadings; one period gives the one-cycle difference): see TwistWindow.
  /// It refers to twist_window_s / 2 before the cycle's reading.
  double twist_window_s = 0.02;
  /// One wheel and one steering encoder count, rad, for the twist covariance (0: unknown,
  /// and then no covariance is published). The daemon takes them from the robot model.
  double wheel_encoder_resolution_rad = 0.0;
  double steer_encoder_resolution_rad = 0.0;
  /// How often a non-real-time thread re-measures the offset of the realtime clock (ROS
  /// time) from the loop's monotonic clock, s (see ClockOffset).
  double clock_offset_refresh_s = 1.0;
  /// Run samples per second handed to a recorder through take_run_sample(); 0: none; at
  /// most rate_hz. They follow the clock, not a cycle count: a sample is due every
  /// 1 / run_sample_rate_hz from the first cycle and taken at the first cycle within half a
  /// loop period of that, so late or skipped cycles do not slow the rate down. A rate that
  /// divides rate_hz gives evenly spaced samples.
  double run_sample_rate_hz = 0.0;
  /// Gyro and motion capture from outside the hardware plugin (push_gyro(),
  /// push_motion_capture() with MotionCaptureSource::kWatched) and their staleness limits.
  /// A configured gyro replaces the hardware reading's gyro rate with its newest sample.
  ExternalSensorOptions external_sensors;
};

/// Readings in the twist window of `options` (TwistWindowOptions::readings).
/// @throws std::invalid_argument when the window is not finite and positive or needs more
///         than kMaxTwistWindowReadings readings.
std::size_t twist_window_readings(const LoopOptions& options);

/// Sets the encoder resolutions of `options` from the robot model's sensors (one count:
/// 2 pi / counts per revolution; the steering only for an swpc robot).
void set_encoder_resolutions(const RobotModel& robot, LoopOptions& options) noexcept;

/// The model's settings as the loop takes them (the limits and set_encoder_resolutions()).
ModelSettings model_settings(const RobotModel& robot) noexcept;

/// The loop's answer to request_clear() or request_set_pose().
struct LoopReply {
  std::uint64_t id = 0;  ///< the request's id
  bool ok = false;
  /// Clear: the fault that was cleared (ok) or that persists (refused); kNone when there was
  /// nothing to clear. Set-pose: kNone.
  FaultCode fault = FaultCode::kNone;
  FaultDetail detail{};  ///< the cleared or persisting fault's cause, or why a pose was refused
};

// Its buffers are cache-line aligned so that the loop and the other threads do not share
// lines: the padding is the point.
// NOLINTNEXTLINE(clang-analyzer-optin.performance.Padding)
class ControlLoop {
 public:
  /// Not real-time safe. The plugins must be configured and the localization reset; they
  /// must outlive the loop (and a swapped-in localization until it is retired).
  /// `localization_name` is copied (truncated to ShortName).
  /// @throws std::invalid_argument for a rate, timeout or odometry_check limit that is not
  ///         finite and positive.
  ControlLoop(const LoopOptions& options, Hardware& hardware, Drivetrain& drivetrain,
              Localization& localization, const char* localization_name);
  /// Stops the loop if it runs.
  ~ControlLoop();
  ControlLoop(const ControlLoop&) = delete;
  ControlLoop& operator=(const ControlLoop&) = delete;

  /// Not real-time safe. Applies real-time settings where permitted, starts the log thread,
  /// the clock-offset thread and the loop thread, and returns one line per setting that was refused
  /// (the loop then runs SCHED_OTHER and/or without locked memory).
  /// @throws std::system_error when a thread cannot be created; std::logic_error when
  ///         already running.
  std::vector<std::string> start();

  /// Not real-time safe. Stops the loop after a final cycle that commands zero velocity
  /// (zero setpoints written to the hardware), joins the threads, releases the real-time
  /// settings. Idempotent; does nothing when not running.
  void stop() noexcept;

  /// Any thread. Real-time safe.
  [[nodiscard]] bool running() const noexcept { return running_.load(std::memory_order_acquire); }

  /// The command-source thread only (single producer). Real-time safe, wait-free. Publishes
  /// `command` into a latest-value slot: the loop takes the newest command at its next cycle,
  /// and a command it has not taken yet is replaced (under a flood the newest, e.g. a stop,
  /// always wins). Always true (accepted).
  bool push_command(const VelocityCommand& command) noexcept {
    command_.push(command);
    return true;
  }

  /// The external-sensor thread only (single producer). Real-time safe. The loop hands the
  /// newest sample to the localization as HardwareState::motion_capture when the hardware
  /// reading carries none. A sample of the watched source (MotionCaptureSource::kWatched)
  /// must carry its reception time in stamp_s: it feeds that source's staleness watch.
  /// False (dropped) when the ring is full.
  bool push_motion_capture(const MotionCaptureSample& sample,
                           MotionCaptureSource source = MotionCaptureSource::kSwivelTopic) noexcept;

  /// The external-sensor thread only (single producer). Real-time safe. A body-frame gyro
  /// sample; with LoopOptions::external_sensors.gyro enabled the newest one replaces the
  /// hardware reading's gyro rate from the next cycle on (ignored otherwise). False
  /// (dropped) when the ring is full.
  bool push_gyro(const GyroSample& sample) noexcept;

  /// The recording thread only (single consumer). Real-time safe. Copies out the oldest run
  /// sample not taken yet (LoopOptions::run_sample_rate_hz); false when there is none. The
  /// ring holds kRunSampleRingCapacity samples (5 s at 100 Hz): a consumer that falls further
  /// behind loses the newest ones, which shows as a jump in RunSample::sequence.
  bool take_run_sample(RunSample& out) noexcept { return publish_.run_samples().take(out); }

  /// Any thread. Run samples the loop could not hand over because the ring was full.
  [[nodiscard]] std::uint64_t run_samples_dropped() const noexcept {
    return publish_.run_samples().dropped();
  }

  /// Any thread. The time between two run samples the loop produces, s; 0 when it produces
  /// none.
  [[nodiscard]] double run_sample_period_s() const noexcept {
    return publish_.run_samples().period_s();
  }

  static constexpr std::size_t kRunSampleRingCapacity = RunSampleStage::kRingCapacity;

  /// Any thread. Real-time safe (lock-free; retries while the loop writes). The state at the
  /// end of the newest cycle.
  [[nodiscard]] StateSnapshot latest() const noexcept { return publish_.latest(); }

  /// Any non-real-time thread (walks the histograms). Timing of the loop thread's cycles.
  [[nodiscard]] TimingReport timing() const { return timing_.report(); }

  /// Any thread. The histograms behind timing(), e.g. for publishing them as diagnostics.
  [[nodiscard]] const TimingStats& timing_stats() const noexcept { return timing_; }

  /// The swapping thread only. Real-time safe. Asks the loop to take `swap` at a cycle
  /// boundary (the next one; with a drivetrain, the first one at rest): it calls
  /// swap->localization->hand_over() with the outgoing estimate, so that the pose is
  /// continuous, and on success makes the incoming instances active. False for null, a null
  /// localization, or while an earlier swap has not been given back (take_retired_swap(),
  /// withdraw_swap()).
  bool request_swap(LoopSwap* swap) noexcept { return swap_.request(swap); }

  /// The swapping thread only. Real-time safe. The swap the loop let go of (taken or
  /// refused, see LoopSwap), or nullptr while there is none; the instances it holds will
  /// never be called again: destroy and unload them.
  LoopSwap* take_retired_swap() noexcept { return swap_.take_retired(); }

  /// The swapping thread only. Not real-time safe: may wait for the cycle boundary under
  /// way. Takes back `swap` when the loop has not taken it yet (true: it never will, and its
  /// instances were never called). False when the loop already let go of it or is doing so:
  /// take_retired_swap() then returns it.
  bool withdraw_swap(LoopSwap* swap) noexcept { return swap_.withdraw(swap); }

  /// request_swap() of a new localization alone. `name` is copied (truncated to ShortName).
  bool request_localization_swap(Localization* next, const char* name) noexcept {
    return swap_.request_localization(next, name);
  }

  /// The localization instance of the swap the loop let go of (take_retired_swap()), or
  /// nullptr: the outgoing instance, or the incoming one when it refused the hand-over.
  /// `outcome` (optional) says which.
  Localization* take_retired_localization(SwapOutcome* outcome = nullptr) noexcept;

  /// Any thread. Real-time safe. True while a requested swap has not been taken, refused or
  /// withdrawn.
  [[nodiscard]] bool swap_pending() const noexcept { return swap_.pending(); }

  /// Any thread. The localization the loop is using now. Real-time safe.
  [[nodiscard]] Localization* active_localization() const noexcept { return swap_.active(); }

  /// The calibrating thread only. Real-time safe. Hands `calibration` (configured off the
  /// loop; it must outlive its hand-back) to the loop, which starts it at its next cycle
  /// boundary. False for null or while a previous calibration has not been handed back
  /// with take_finished_calibration().
  bool start_calibration(Calibration* calibration) noexcept {
    return calibration_.start(calibration);
  }

  /// The calibrating thread only. Real-time safe. Stops a running calibration with zero
  /// setpoints at the next cycle (mode kIdle); one not yet taken by the loop is handed back
  /// at once. Does nothing when no calibration is in flight.
  void cancel_calibration() noexcept { calibration_.cancel(); }

  /// The calibrating thread only. Real-time safe. The calibration the loop let go of (it
  /// will never be called again: analyse it and destroy it off the loop), or nullptr while
  /// none is; `outcome` (optional) receives how it ended.
  Calibration* take_finished_calibration(CalibrationOutcome* outcome = nullptr) noexcept {
    return calibration_.take_finished(outcome);
  }

  /// Any thread. Real-time safe. True from start_calibration() until the instance is
  /// taken back.
  [[nodiscard]] bool calibration_in_flight() const noexcept { return calibration_.in_flight(); }

  /// Any thread. Real-time safe. The calibration the loop is running now, or nullptr.
  [[nodiscard]] Calibration* active_calibration() const noexcept { return calibration_.active(); }

  /// Any thread. Real-time safe. Requests leaving kSafeStop: honoured at the first cycle
  /// without a fault (the request waits while the cause persists). Ignored when no fault
  /// is latched.
  void clear_fault() noexcept { clear_requested_.store(true, std::memory_order_release); }

  /// The requesting thread only. Real-time safe. Asks the loop, once, to leave the fault it
  /// reports; answered through take_reply() at the next cycle:
  ///  - a latched fault (kSafeStop): cleared when that cycle runs without a fault, else
  ///    refused with the fault and its cause (the request does not wait);
  ///  - a command timeout: refused (the cause, a missing command stream, persists until a
  ///    fresh command resumes by itself);
  ///  - another transient fault (a rejected command, a cancelled calibration): cleared;
  ///  - none: ok, nothing to clear.
  /// A request replaces one the loop has not taken yet (that one is never answered).
  void request_clear(std::uint64_t id) noexcept;

  /// The requesting thread only. Real-time safe. Asks the loop to set the estimate to `pose`
  /// at its next cycle boundary through the active localization's hand_over() (the hot-swap
  /// path; the covariance only when pose.has_covariance). Answered through take_reply(): ok,
  /// or refused with the plugin's reason (the estimate stays as it was; no fault).
  void request_set_pose(const PoseEstimate& pose, std::uint64_t id) noexcept;

  /// The requesting thread only. Real-time safe. The answer to the newest request, once.
  bool take_reply(LoopReply& out) noexcept { return replies_.take(out); }

  /// The requesting thread only. Not real-time safe: waits up to `timeout_s`. Stops the
  /// loop's calls to the hardware (read and write) from a cycle boundary on, so that a
  /// lifecycle method (Hardware::activate()) can run off the loop; the loop keeps cycling and
  /// publishing meanwhile. Granted only while a fault is latched and the last setpoints
  /// written were zero (the robot stopped); returns false when refused or not granted in
  /// time. Call resume_hardware() after a true return.
  bool pause_hardware(double timeout_s) noexcept;

  /// The requesting thread only. Real-time safe. Lets the loop call the hardware again from
  /// its next cycle (the first reading after a pause gives no odometry).
  void resume_hardware() noexcept;

  /// Any thread. Real-time safe. From the next cycle on, velocity commands are ignored, a
  /// calibration is cancelled and the robot is brought to rest within the controlled stop's
  /// limits while the loop keeps running (StateSnapshot::stopping). Irreversible: for
  /// shutting down. `requested_s` (the loop's clock, now_s()) is when the stop was asked
  /// for: the deceleration counts from then, not from the cycle that takes the request.
  /// Later calls change nothing.
  void request_controlled_stop(double requested_s) noexcept { command_.request_stop(requested_s); }

  /// Runs one cycle on the calling thread at monotonic time `now_s` (tests, benchmarks).
  /// Real-time safe. Must not be called while the loop thread runs. Does not record timing.
  void run_cycle(double now_s) noexcept;

  /// Any thread. Real-time safe. CLOCK_MONOTONIC, seconds: the clock of `received_s`.
  // A member, so that callers read the loop's clock through the loop.
  // NOLINTNEXTLINE(readability-convert-member-functions-to-static)
  [[nodiscard]] double now_s() const noexcept { return monotonic_s(); }

  /// Any thread. The offset that maps the loop's stamps to ROS time
  /// (StateSnapshot::ros_stamp_ns): measured at construction, refreshed every
  /// clock_offset_refresh_s by a thread of its own while the loop runs.
  [[nodiscard]] const ClockOffset& clock_offset() const noexcept { return clock_offset_; }

  /// Any thread. Real-time safe. The loop period, seconds.
  [[nodiscard]] double period_s() const noexcept { return period_s_; }

  /// The loop's log; tests may drain() it while the loop thread is not running.
  [[nodiscard]] RtLog& log() noexcept { return log_; }

 private:
  void thread_main(std::promise<std::string>& scheduling_warning) noexcept;
  void cycle(double now_s, bool final_stop) noexcept;
  void take_pending_swap(double now_s) noexcept;
  void apply_model(const ModelSettings& model) noexcept;
  bool hold_hardware() noexcept;
  void take_request(double now_s, std::uint64_t& clear_id) noexcept;
  void take_clear(double now_s, std::uint64_t clear_id) noexcept;
  void answer_clear(std::uint64_t id, double now_s) noexcept;
  void clear_latched_fault(double now_s) noexcept;
  void end_cycle(double now_s) noexcept {
    last_cycle_s_ = now_s;
    has_last_cycle_ = true;
  }

  LoopOptions options_;
  double period_s_;
  std::int64_t period_ns_;
  Hardware& hardware_;
  Drivetrain* drivetrain_;  // the loop's; replaced by a model swap
  std::uint32_t module_count_;

  // Cross-thread state; the stages below hold their own (rings, slots, swap and calibration
  // hand-over).
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> clear_requested_{false};
  // Hardware pause handshake (pause_hardware()): requester -> loop -> requester.
  enum class HardwareAccess : std::uint8_t { kCalling, kPauseRequested, kPaused, kPauseRefused };
  std::atomic<HardwareAccess> hardware_access_{HardwareAccess::kCalling};
  struct LoopRequest {
    enum class Kind : std::uint8_t { kClear, kSetPose } kind = Kind::kClear;
    std::uint64_t id = 0;
    PoseEstimate pose;
  };
  LatestValue<LoopRequest> requests_;
  LatestValue<LoopReply> replies_;
  TimingStats timing_;
  RtLog log_;

  // The stages, in the order a cycle runs them (docs/architecture.md "One cycle of the loop").
  LoopEvents events_{log_};  // faults and log records, shared by the stages
  PluginGuard guard_;        // around every plugin call
  SwapStage swap_;           // the active localization; hot swaps
  CalibrationStage calibration_;
  ExternalSensorStage sensors_;
  HardwareReadStage read_;
  OdometryStage odometry_;
  CommandStage command_;  // mode and command limiting; the controlled stop
  WriteStage write_;
  PublishStage publish_;  // the snapshot and the run samples

  // Loop-thread state.
  double last_cycle_s_ = 0.0;
  bool has_last_cycle_ = false;
  bool hardware_paused_ = false;  // the loop's view of hardware_access_
  bool clear_pending_ = false;    // a request_clear() taken this cycle

  // Non-real-time ownership.
  ClockOffset clock_offset_;
  std::mutex clock_mutex_;
  std::condition_variable_any clock_wake_;
  std::jthread clock_thread_;
  std::thread thread_;
  CpuDmaLatencyRequest dma_latency_;
};

}  // namespace swivel::rt
