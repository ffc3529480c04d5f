// SPDX-License-Identifier: Apache-2.0
#pragma once
// The daemon's DDS side. A publisher thread reads the loop's newest state snapshot at the
// publish rate and writes RobotState, ModuleStates (and, with ROS 2 enabled, odometry, the
// odom -> base transform and joint states); it writes Diagnostics (and ROS 2's
// DiagnosticArray) at the diagnostics rate. A subscriber thread waits on the command
// readers and hands each accepted sample to a callback, which the daemon wires into the
// loop's lock-free rings or its request queue. Requests (Request, SetPose) are answered with
// publish_reply(). The bridge knows nothing of the loop beyond these callbacks.
//
// Thread safety: the callbacks run on the bridge's threads (read_state and
// read_diagnostics on the publisher thread, the others on the subscriber thread), never on
// the caller's. publish_calibration() and publish_reply() may be called from any thread.
// Nothing here is real-time safe.

#include <dds/dds.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "swivel/dds/options.hpp"
#include "swivel/dds/publish_rate_meter.hpp"
#include "swivel/dds/sensor_inputs.hpp"
#include "swivel/rt/state_snapshot.hpp"
#include "swivel/types.hpp"

namespace swivel::dds {

/// Percentiles of one timing histogram, microseconds.
struct TimingPercentiles {
  double p50_us = 0.0;
  double p99_us = 0.0;
  double p999_us = 0.0;
  double max_us = 0.0;
};

/// What the daemon reports as Diagnostics (the bridge adds robot id, stamp and its own
/// command counters).
struct DiagnosticsSample {
  double uptime_s = 0.0;
  double loop_rate_hz = 0.0;      ///< configured
  double measured_rate_hz = 0.0;  ///< over the daemon's last window
  TimingPercentiles lateness;     ///< wake-up lateness, us
  TimingPercentiles cycle_time;   ///< cycle execution time, us
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;
  std::uint64_t fault_count = 0;
  LoopMode mode = LoopMode::kIdle;  ///< the loop's mode (ROS 2 diagnostics level)
  FaultCode fault = FaultCode::kNone;
  std::string fault_detail;  ///< the active fault's cause ("" when healthy)
  std::string hardware_plugin;
  std::string drivetrain_plugin;
  std::string localization_plugin;
  std::string robot_model;         ///< the model file in effect
  std::uint32_t reload_count = 0;  ///< configuration reloads attempted
  bool last_reload_ok = true;
  std::string last_reload_result;  ///< "" before the first reload
  bool restart_required = false;   ///< a changed setting needs a restart
};

/// A request addressed to this robot (Request topic).
struct RequestSample {
  std::string verb;              ///< "reload", "calibrate" or "clear"
  std::string argument;          ///< verb-specific, "" when none
  std::uint64_t request_id = 0;  ///< echoed in the Reply
};

/// A pose to set, from SetPose or the ROS 2 initialpose topic.
struct SetPoseSample {
  std::uint64_t request_id = 0;  ///< echoed in the Reply (SetPose only)
  PoseEstimate pose;             ///< world frame; the covariance only when the sender gave one
  bool wants_reply = true;       ///< false for ROS 2's initialpose, which expects no answer
  std::string source;            ///< the topic it came from, for messages
};

/// The answer to one request (Reply topic).
struct ReplySample {
  std::uint64_t request_id = 0;
  std::string verb;  ///< the request's verb, "set_pose" for a SetPose
  bool ok = false;   ///< done or accepted; false: refused
  std::string text;  ///< what was done, or why it was refused
};

/// Calibrated geometry of one module with one-sigma uncertainties.
struct ModuleCalibrationSample {
  double x_m = 0.0, y_m = 0.0, delta_rad = 0.0, d_m = 0.0, r_m = 0.0;
  double sigma_x_m = 0.0, sigma_y_m = 0.0, sigma_delta_rad = 0.0, sigma_d_m = 0.0, sigma_r_m = 0.0;
};

/// Progress or result of a calibration run (CalibrationResult topic).
struct CalibrationSample {
  std::string status;  ///< idle | running | done | failed | cancelled
  double progress = 0.0;
  std::string text;
  std::vector<ModuleCalibrationSample> modules;  ///< at most kMaxModules
};

/// How the bridge reaches the daemon. Only read_state is required.
struct DdsCallbacks {
  /// Copies the loop's newest snapshot into the argument; false when there is none yet.
  std::function<bool(StateSnapshot&)> read_state{};
  /// A velocity command for this robot, with received_s set to the reception time
  /// (CLOCK_MONOTONIC). Return false when it could not be queued (counted as dropped).
  std::function<bool(const VelocityCommand&)> on_command{};
  /// A motion-capture sample for this robot (stamp_s on the daemon's CLOCK_MONOTONIC).
  std::function<bool(const MotionCaptureSample&)> on_motion_capture{};
  /// A body-frame gyro sample from the ROS 2 IMU topic (dds.ros2.imu), received_s on
  /// CLOCK_MONOTONIC at reception.
  std::function<bool(const rt::GyroSample&)> on_gyro{};
  /// A motion-capture sample from the ROS 2 pose topic (dds.ros2.mocap_pose), stamp_s on
  /// CLOCK_MONOTONIC at reception.
  std::function<bool(const MotionCaptureSample&)> on_pose_motion_capture{};
  /// The loop's health; when empty, no Diagnostics are published.
  std::function<DiagnosticsSample()> read_diagnostics{};
  /// A request ("reload", ...) for this robot.
  std::function<void(const RequestSample&)> on_request{};
  /// A pose to set for this robot (SetPose, or ROS 2 initialpose when enabled).
  std::function<void(const SetPoseSample&)> on_set_pose{};
};

/// Counters of the bridge's own work, for diagnostics and tests.
struct BridgeCounters {
  std::uint64_t states_published = 0;
  std::uint64_t commands_received = 0;  ///< accepted by on_command
  std::uint64_t commands_dropped = 0;   ///< refused by on_command, or no callback
  std::uint64_t commands_ignored = 0;   ///< addressed to another robot
  std::uint64_t commands_stale = 0;     ///< ROS 2 TwistStamped older than cmd_vel_max_age_s
  std::uint64_t motion_captures_received = 0;
  std::uint64_t requests_received = 0;  ///< Request and SetPose (initialpose included)
  std::uint64_t replies_published = 0;
  /// Publisher rounds that failed (logged at the 1st, 2nd, 4th, 8th, ...).
  std::uint64_t publish_failures = 0;
  /// RobotStates written per second over the publisher's last window (PublishRateMeter).
  double achieved_publish_rate_hz = 0.0;
  SensorCounters sensors;  ///< the ROS 2 sensor topics (dds.ros2.imu, mocap_pose)
};

class DdsBridge {
 public:
  /// Creates the participant, topics, writers and readers (nothing runs yet).
  /// @param robot_id  the key of every sample this daemon writes and accepts
  /// @throws DdsError when DDS refuses an entity; std::invalid_argument when robot_id is
  ///         empty or read_state is missing.
  DdsBridge(DdsOptions options, std::string robot_id, DdsCallbacks callbacks);
  /// Stops the threads and deletes every DDS entity.
  ~DdsBridge();
  DdsBridge(const DdsBridge&) = delete;
  DdsBridge& operator=(const DdsBridge&) = delete;
  DdsBridge(DdsBridge&&) = delete;
  DdsBridge& operator=(DdsBridge&&) = delete;

  /// Starts the publisher and subscriber threads. Call once.
  void start();
  /// Stops and joins both threads. Idempotent.
  void stop() noexcept;

  /// Writes one CalibrationResult now (any thread). @throws DdsError
  void publish_calibration(const CalibrationSample& sample);

  /// Writes one Reply now (any thread). The newest replies stay registered so that a
  /// reliable reader still gets them; older instances are unregistered, which bounds the
  /// writer's memory however many requests arrive. @throws DdsError
  void publish_reply(const ReplySample& reply);

  [[nodiscard]] BridgeCounters counters() const;
  /// What the bridge found wrong, "; "-separated, "" when nothing: a cmd_vel publisher of the
  /// other type (CmdVelTypeCheck), states published short of the attainable rate. Published
  /// in Diagnostics.dds_warnings and the ROS 2 diagnostics.
  [[nodiscard]] std::string dds_warnings() const;
  [[nodiscard]] const std::string& robot_id() const { return robot_id_; }
  /// The bridge's participant, for other writers of the daemon (RunSamplePublisher); valid
  /// while the bridge lives.
  [[nodiscard]] dds_entity_t participant() const;
  [[nodiscard]] const DdsOptions& options() const { return options_; }

 private:
  struct Entities;

  void publish_loop(const std::stop_token& stop);
  void subscribe_loop(const std::stop_token& stop);
  void publish_state(const StateSnapshot& snapshot);
  void publish_diagnostics(const DiagnosticsSample& sample);
  void publish_ros2_state(const StateSnapshot& snapshot);
  void publish_ros2_diagnostics(const DiagnosticsSample& sample, const std::string& dds_warnings);
  void measure_publish_rate(PublishRateMeter& rate, std::uint64_t newest_cycle);
  void announce_node();
  void take_commands();
  void take_ros2_commands();
  void take_motion_capture();
  void take_requests();
  void take_set_poses();
  void take_ros2_initialposes();
  void deliver_command(const Twist2& twist);

  DdsOptions options_;
  std::string robot_id_;
  DdsCallbacks callbacks_;
  std::string odom_frame_;  ///< frame_prefix + odom_frame_id
  std::string base_frame_;  ///< frame_prefix + base_frame_id
  std::unique_ptr<Entities> dds_;
  std::jthread publisher_;
  std::jthread subscriber_;

  std::atomic<std::uint64_t> states_published_{0};
  std::atomic<std::uint64_t> commands_received_{0};
  std::atomic<std::uint64_t> commands_dropped_{0};
  std::atomic<std::uint64_t> commands_ignored_{0};
  std::atomic<std::uint64_t> commands_stale_{0};
  std::atomic<std::uint64_t> motion_captures_received_{0};
  std::atomic<std::uint64_t> requests_received_{0};
  std::atomic<std::uint64_t> replies_published_{0};
  std::atomic<std::uint64_t> publish_failures_{0};
  std::atomic<double> achieved_publish_rate_hz_{0.0};    ///< written by the publisher thread
  std::atomic<double> attainable_publish_rate_hz_{0.0};  ///< written by the publisher thread
  std::atomic<bool> publish_rate_short_{false};          ///< written by the publisher thread
  std::uint64_t next_command_sequence_ = 0;              ///< subscriber thread only
  bool warned_zero_stamp_ = false;                       ///< subscriber thread only
};

/// Fills a ROS 2 style quaternion (x, y, z, w) for a rotation of `yaw_rad` about z.
void yaw_to_quaternion(double yaw_rad, double& x, double& y, double& z, double& w) noexcept;

/// The rotation about z of a quaternion (x, y, z, w), rad; NaN when it is not a rotation
/// (a norm far from 1, or not finite).
double quaternion_to_yaw(double x, double y, double z, double w) noexcept;

}  // namespace swivel::dds
