// SPDX-License-Identifier: Apache-2.0
#pragma once
// Plain data exchanged on the real-time loop. Every type here is trivially copyable so that
// it can cross threads through the lock-free buffers. Frames: robot (body) frame x forward,
// y left; world frame fixed; yaw counter-clockwise positive. SI units, radians.

#include <array>
#include <cstdint>
#include <type_traits>

namespace swivel {

/// Most modules (wheels or casters) a drivetrain may have; fixes the size of loop data.
inline constexpr std::uint32_t kMaxModules = 16;

/// Result of a real-time call. Hot-path functions never throw; they return this.
enum class Status : std::uint8_t { kOk = 0, kError = 1 };

struct Pose2 {
  double x_m = 0.0;      ///< world frame
  double y_m = 0.0;      ///< world frame
  double yaw_rad = 0.0;  ///< world frame, counter-clockwise positive
};

struct Twist2 {
  double vx_mps = 0.0;    ///< robot frame, forward
  double vy_mps = 0.0;    ///< robot frame, left
  double wz_radps = 0.0;  ///< counter-clockwise positive
};

/// Pose with its covariance (row-major over x, y, yaw; m^2, m*rad, rad^2).
struct PoseEstimate {
  Pose2 pose;
  std::array<double, 9> covariance{};
  bool has_covariance = false;
};

/// One motion-capture sample of the robot origin and heading (world frame).
struct MotionCaptureSample {
  bool valid = false;
  double stamp_s = 0.0;  ///< monotonic time the sample was taken
  Pose2 pose;
};

/// Sensor readings of one cycle. Differential robots use modules 0 (left) and 1 (right)
/// and leave steering at zero.
struct HardwareState {
  double stamp_s = 0.0;  ///< monotonic time of the reading, s
  std::uint32_t module_count = 0;
  std::array<double, kMaxModules> wheel_angle_rad{};  ///< cumulative encoder angle, rad
  std::array<double, kMaxModules> steer_angle_rad{};  ///< measured steering (true - offset), rad
  double gyro_wz_radps = 0.0;                         ///< yaw rate, rad/s
  bool gyro_valid = false;
  MotionCaptureSample motion_capture;  ///< valid only in cycles where a new sample arrived
};

/// How one module's actuators are driven.
enum class ModuleDriveMode : std::uint8_t {
  kVelocity = 0,   ///< wheel rate and steering rate setpoints are tracked
  kLocked = 1,     ///< steering and wheel held still (calibration pivot)
  kFreeSteer = 2,  ///< wheel rate tracked, steering left free to self-align
  /// Wheel driven by a constant torque, steering free (docs/methods.md §1's calibration drive): the
  /// wheel rolls without slipping at whatever rate the motion asks; the wheel-rate setpoint
  /// only sets the pace (a simulator) or the torque level (hardware).
  kTorque = 3,
};

/// Actuator setpoints of one cycle.
struct ActuatorCommand {
  std::uint32_t module_count = 0;
  std::array<double, kMaxModules> wheel_rate_radps{};
  std::array<double, kMaxModules> steer_rate_radps{};
  std::array<ModuleDriveMode, kMaxModules> mode{};
};

/// Odometry from one pair of consecutive readings (drivetrain forward kinematics).
struct OdometryIncrement {
  double dt_s = 0.0;
  Pose2 delta;            ///< motion over dt in the robot frame at the start of the step
  Twist2 twist;           ///< mean body twist over dt
  double residual = 0.0;  ///< least-squares residual of the kinematic fit (slip indicator)
  bool valid = false;
};

/// Per-module state for the state snapshot.
struct ModuleState {
  double steer_angle_rad = 0.0;        ///< measured
  double steer_rate_cmd_radps = 0.0;   ///< commanded
  double wheel_rate_cmd_radps = 0.0;   ///< commanded
  double wheel_rate_meas_radps = 0.0;  ///< measured
};

static_assert(std::is_trivially_copyable_v<HardwareState>);
static_assert(std::is_trivially_copyable_v<ActuatorCommand>);
static_assert(std::is_trivially_copyable_v<OdometryIncrement>);
static_assert(std::is_trivially_copyable_v<PoseEstimate>);

}  // namespace swivel
