// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the real-time loop publishes every cycle (into a lock-free snapshot buffer) and
// what it accepts (through lock-free rings). Trivially copyable by construction.

#include <array>
#include <cstdint>
#include <type_traits>

#include "swivel/types.hpp"

namespace swivel {

enum class LoopMode : std::uint8_t {
  kIdle = 0,         ///< no command yet: zero velocity
  kVelocity = 1,     ///< following velocity commands
  kCalibration = 2,  ///< a calibration procedure drives the actuators
  kSafeStop = 3,     ///< controlled stop after a fault; zero velocity until cleared
};

/// Why the loop stopped the robot (or rejected something). kNone when healthy.
enum class FaultCode : std::uint16_t {
  kNone = 0,
  kCommandTimeout,        ///< newest velocity command older than its timeout
  kNonFiniteCommand,      ///< NaN/inf in a velocity command (rejected)
  kNonFiniteSensor,       ///< NaN/inf from the hardware plugin
  kHardwareError,         ///< hardware plugin returned kError
  kDrivetrainError,       ///< drivetrain plugin returned kError
  kLocalizationError,     ///< localization plugin returned kError or a non-finite pose
  kCalibrationError,      ///< calibration procedure failed or was cancelled
  kOdometryInconsistent,  ///< sustained disagreement: encoders vs gyro, or drivetrain residual
  kSensorStale,           ///< a configured external sensor (DDS gyro, motion capture) went silent
};

/// Stable snake_case name of a fault (status lines, logs, DDS). Header-only so that the DDS
/// bridge needs no real-time runtime for it.
inline const char* fault_code_name(FaultCode code) noexcept {
  switch (code) {
    case FaultCode::kNone: return "none";
    case FaultCode::kCommandTimeout: return "command_timeout";
    case FaultCode::kNonFiniteCommand: return "non_finite_command";
    case FaultCode::kNonFiniteSensor: return "non_finite_sensor";
    case FaultCode::kHardwareError: return "hardware_error";
    case FaultCode::kDrivetrainError: return "drivetrain_error";
    case FaultCode::kLocalizationError: return "localization_error";
    case FaultCode::kCalibrationError: return "calibration_error";
    case FaultCode::kOdometryInconsistent: return "odometry_inconsistent";
    case FaultCode::kSensorStale: return "sensor_stale";
  }
  return "unknown";
}

/// A velocity command as it enters the loop.
struct VelocityCommand {
  Twist2 twist;
  double received_s = 0.0;  ///< monotonic time it was received (age = now - received_s)
  std::uint64_t sequence = 0;
};

/// Fixed-size, NUL-terminated name (plugin names, fault details) that can cross threads.
using ShortName = std::array<char, 32>;

/// Fixed-size, NUL-terminated cause of a fault (a plugin's last_error() or the loop's own
/// text, truncated), the same size as RtLog's detail.
using FaultDetail = std::array<char, 64>;

/// The loop's state at the end of one cycle.
struct StateSnapshot {
  std::uint64_t cycle = 0;
  double stamp_s = 0.0;  ///< monotonic time of the cycle's reading
  /// stamp_s in ROS time: CLOCK_REALTIME (Unix time), ns, through the loop's measured
  /// offset of the realtime clock from the monotonic one (rt::ClockOffset).
  std::int64_t ros_stamp_ns = 0;
  PoseEstimate estimate;  ///< localization output, world frame
  /// Body twist from the encoders (the drivetrain's forward kinematics over the loop's
  /// twist window, see TwistWindow), robot frame; it refers to half the window before
  /// stamp_s.
  Twist2 odometry_twist;
  /// Covariance of odometry_twist from the encoders' quantization, row-major over (vx, vy,
  /// wz): m^2/s^2, m rad/s^2, rad^2/s^2.
  std::array<double, 9> twist_covariance{};
  bool has_twist_covariance = false;
  Twist2 command_twist;  ///< twist applied this cycle after limits, robot frame
  double odometry_residual = 0.0;
  double gyro_wz_radps = 0.0;
  std::uint32_t module_count = 0;
  std::array<ModuleState, kMaxModules> modules{};
  LoopMode mode = LoopMode::kIdle;
  FaultCode fault = FaultCode::kNone;    ///< active fault (kNone when healthy)
  FaultDetail fault_detail{};            ///< the active fault's cause ("" when healthy)
  std::uint64_t fault_count = 0;         ///< faults raised since start
  ShortName localization_plugin{};       ///< active localization plugin
  std::uint64_t localization_swaps = 0;  ///< hot swaps taken by the loop
  std::uint64_t model_swaps = 0;         ///< robot-model swaps (new drivetrain) among them
  bool has_truth = false;                ///< simulation: the true pose is known
  Pose2 truth;
  /// The cycle's raw hardware reading (for run logs): cumulative encoder angles, rad, and
  /// measured steering angles, rad, per module.
  std::array<double, kMaxModules> wheel_angle_rad{};
  std::array<double, kMaxModules> steer_angle_rad{};
  /// The encoder rates behind odometry_twist: each module's wheel and steering rate, rad/s,
  /// fitted over the twist window (they refer to its middle); valid with has_joint_rates.
  std::array<double, kMaxModules> wheel_rate_radps{};
  std::array<double, kMaxModules> steer_rate_radps{};
  bool has_joint_rates = false;
  /// The hardware is in its error state: on_error() was called and no clear has succeeded
  /// since (a clear re-activates it first).
  bool hardware_in_error = false;
  /// ControlLoop::request_controlled_stop() was taken: commands are ignored and the robot is
  /// brought to rest before the daemon shuts down.
  bool stopping = false;
};

static_assert(std::is_trivially_copyable_v<VelocityCommand>);
static_assert(std::is_trivially_copyable_v<StateSnapshot>);

}  // namespace swivel
