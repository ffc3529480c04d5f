// SPDX-License-Identifier: Apache-2.0
#pragma once
// The robot model of README "Configuration reference: robot model": plain data shared by the
// daemon, the plugins, the simulator and the offline tools. Loading and saving YAML lives in
// robot_model_io.hpp so that maths libraries can use these types without yaml-cpp.

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace swivel {

struct DifferentialParams {
  double wheel_radius_left_m = 0.075;
  double wheel_radius_right_m = 0.075;
  double track_width_m = 0.40;
};

/// One single-wheel powered caster (docs/methods.md §1 conventions: heading u = (cos phi, sin phi),
/// contact point c = p - d u, measured steering = true - steering_offset).
struct SwpcModuleParams {
  double x_m = 0.0;                  ///< steering axis, robot frame
  double y_m = 0.0;                  ///< steering axis, robot frame
  double steering_offset_rad = 0.0;  ///< delta: true steering = measured + delta
  double caster_offset_m = 0.020;    ///< d: steering axis to wheel contact, horizontal
  double wheel_radius_m = 0.055;     ///< r
};

struct GyroParams {
  double scale = 1.0;  ///< k_g: measured = scale * true + bias + noise
  double bias_rad_s = 0.0;
  double noise_rad_s = 0.0;  ///< white noise standard deviation
};

struct MotionCaptureParams {
  double position_noise_m = 0.0003;
  double yaw_noise_rad = 0.001;
  double rate_hz = 100.0;
};

struct SensorParams {
  /// Encoder counts per revolution of the wheel (or steering axis): real-valued, since a
  /// geared motor's are not an integer (43.7:1 x 64 counts = 2796.8). Finite and > 0.
  double wheel_encoder_counts_per_rev = 4096.0;
  double steering_encoder_counts_per_rev = 4096.0;
  GyroParams gyro;
  MotionCaptureParams motion_capture;
};

/// What the robot's own motion controller enforces (the robot model's `limits:`). Read by the
/// simulator, the model-gap replay and the daemon's command limiter; an absent limit is not
/// applied. The first three keys are the common motion-controller ones; the velocity and jerk
/// limits are Swivel's.
struct MotionLimits {
  std::optional<double> linear_velocity_mps;  ///< body speed, per axis (x, y)
  std::optional<double> angular_velocity_radps;
  std::optional<double> linear_acceleration_mps2;  ///< body, per axis (x, y)
  std::optional<double> angular_acceleration_radps2;
  std::optional<double> linear_jerk_mps3;  ///< body, per axis (x, y)
  std::optional<double> angular_jerk_radps3;
  std::optional<double> steering_rate_radps;  ///< swpc: per module

  [[nodiscard]] bool any() const {
    return linear_velocity_mps || angular_velocity_radps || linear_acceleration_mps2 ||
           angular_acceleration_radps2 || linear_jerk_mps3 || angular_jerk_radps3 ||
           steering_rate_radps;
  }
};

enum class DrivetrainKind { kDifferential, kSwpc };

/// A named model extension and its parameters, e.g. gyro_bias: {bias_rad_s: 0.006}.
using EffectParams = std::map<std::string, double>;

struct RobotModel {
  std::string name;
  DrivetrainKind drivetrain = DrivetrainKind::kDifferential;
  DifferentialParams differential;        ///< used when drivetrain is differential
  std::vector<SwpcModuleParams> modules;  ///< used when drivetrain is swpc
  SensorParams sensors;
  MotionLimits limits;                          ///< absent keys: no limit
  std::map<std::string, EffectParams> effects;  ///< empty in a nominal model
  std::string source_file;                      ///< where it was read from, for messages

  [[nodiscard]] std::size_t module_count() const {
    return drivetrain == DrivetrainKind::kDifferential ? 2U : modules.size();
  }
};

}  // namespace swivel
