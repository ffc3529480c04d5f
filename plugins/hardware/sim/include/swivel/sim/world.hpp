// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulated world: a robot that moves with its TRUE model (parameters plus named
// effects, see effects.hpp) while whoever commands it uses a nominal model, so that
// kinematic errors show up as odometry drift exactly as on a real robot.
//
// Kinematic simulation (no dynamics), fixed sub-steps for determinism:
//  - differential: the wheels' ground rates give the twist through the true radii and
//    track (differential::forward);
//  - swpc: each module in one of three modes (ModuleDriveMode):
//      kVelocity   wheel and steering rates tracked; with every module in this mode the
//                  twist is the least-squares forward kinematics of the true geometry
//                  (swpc::forward), or, with servos that yield to their tyres
//                  (SimOptions::caster_forces), the balance of the tyres' and servos' forces
//                  (caster_forces.hpp): each steering rate is then the servo's reference's,
//                  and the caster follows as far as its tyre lets it;
//      kFreeSteer  wheel rate tracked, steering free: the module contributes its rolling
//                  equation and its steering follows the no-lateral-slip condition
//                  phi_dot = (n . v_s)/d - w, so the caster self-aligns;
//      kTorque     as kFreeSteer for the pace, but the wheel rolls without slipping: its
//                  encoder follows the contact point's motion, as a torque-driven wheel's does;
//      kLocked     wheel and steering held: its contact point cannot move, so the robot can
//                  only rotate about it; the rotation rate is the least-squares fit of the
//                  other modules' equations (the calibration motion of docs/methods.md §1).
// Sensors: quantized wheel and steering encoders (steering reads true - steering offset,
// unwrapped like a multi-turn encoder), a gyro (scale * true + bias + white noise; the
// true rate is the mean over the interval since the previous read, as an integrating
// sensor reports it), motion capture of the origin and heading with noise at the model's
// rate. Non-systematic errors (wheel slip, lateral scrub) are seeded Gauss-Markov
// processes, off by default. Same model, options and call sequence -> same output.

#include <array>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "swivel/robot_model.hpp"
#include "swivel/sim/caster_forces.hpp"
#include "swivel/sim/effects.hpp"
#include "swivel/types.hpp"

namespace swivel::sim {

/// Random errors outside any kinematic model. Zero standard deviations switch them off.
struct NonSystematicErrors {
  /// Relative error of each wheel's ground speed, 1-sigma (e.g. 0.01 = 1 %).
  double wheel_slip_std = 0.0;
  /// Lateral scrub: body velocity perpendicular to the motion as a fraction of the body
  /// speed, 1-sigma.
  double lateral_scrub_std = 0.0;
  /// Correlation time of both first-order Gauss-Markov processes, s.
  double correlation_time_s = 0.5;
};

struct SimOptions {
  std::uint64_t seed = 1;
  /// Largest integration step; step(dt) splits dt into equal sub-steps no longer than this.
  double substep_s = 0.001;
  /// Gyro white noise and motion-capture noise from the model's sensor parameters.
  bool sensor_noise = true;
  /// Encoder quantization (counts per revolution from the model).
  bool quantize_encoders = true;
  bool motion_capture = true;
  NonSystematicErrors nonsystematic;
  /// Whether the body moves. Off, only the actuators run (wheel and steering angles, drive
  /// lags, sensor latency) and the pose and gyro stay still: all a replay of actuator
  /// commands needs, at a fraction of the cost. Drive modes other than kVelocity need the
  /// body's motion and move it whatever this says.
  bool move_body = true;
  Pose2 start_pose;
  /// True steering angles at t = 0 (swpc), rad.
  std::array<double, kMaxModules> initial_steer_rad{};
  /// Steering servos that yield to their tyres (swpc); off with its yield at 0.
  CasterForces caster_forces;
};

class World {
 public:
  /// Not real-time safe (allocates the sensor-delay history).
  /// @throws std::invalid_argument for invalid effects (see validate_effects) or options.
  World(const RobotModel& true_model, const SimOptions& options);

  /// Real-time safe. Advances time by `dt_s` under `command`. kError, with nothing changed,
  /// for a non-finite or negative dt, a non-finite setpoint, an unknown mode or a module
  /// count different from the robot's (see last_error()).
  Status step(double dt_s, const ActuatorCommand& command) noexcept;

  /// Real-time safe. The sensor readings now. A motion-capture sample taken since the
  /// previous read is reported once (the latest one when several were taken).
  void read(HardwareState& out) noexcept;

  [[nodiscard]] double time_s() const noexcept { return t_s_; }
  /// True pose of the robot origin (world frame).
  [[nodiscard]] const Pose2& true_pose() const noexcept { return pose_; }
  /// True body twist of the last sub-step.
  [[nodiscard]] const Twist2& true_twist() const noexcept { return twist_; }
  /// True steering angle of module i (swpc), unwrapped, rad.
  [[nodiscard]] double true_steer_rad(std::size_t i) const noexcept { return modules_[i].phi_rad; }
  /// Real-time safe. What module i's steering encoder reads now (sensor latency, offset and
  /// quantization as in read()), without taking a reading: for a controller that runs
  /// between the readings a log keeps.
  [[nodiscard]] double steer_reading_rad(std::size_t i) const noexcept;
  /// Real-time safe. True steering angle of module i as the sensors see it now: late by the
  /// sensor latency, unwrapped, without offset or quantization, rad.
  [[nodiscard]] double sensed_steer_rad(std::size_t i) const noexcept;
  /// Real-time safe. Turns module i's steering by `delta_rad`, now and in the history the
  /// sensor latency reads: for a replay that re-seats a caster on where a log shows it.
  void turn_steering(std::size_t i, double delta_rad) noexcept;
  /// Sub-steps whose balance of caster forces did not converge (their last iterate was used).
  [[nodiscard]] std::uint64_t caster_force_failures() const noexcept {
    return caster_force_failures_;
  }
  /// True steering rate of module i over the last sub-step, rad/s.
  [[nodiscard]] double true_steer_rate_radps(std::size_t i) const noexcept {
    return modules_[i].steer_rate_radps;
  }
  /// True cumulative wheel angle of module i, rad.
  [[nodiscard]] double true_wheel_rad(std::size_t i) const noexcept { return modules_[i].psi_rad; }
  /// World position of module i's wheel contact point (swpc), or of its wheel centre
  /// projected on the floor (differential).
  [[nodiscard]] Pose2 contact_point_world(std::size_t i) const noexcept;
  /// The world's physical parameters (model + effects).
  [[nodiscard]] const PlantParams& plant() const noexcept { return plant_; }
  [[nodiscard]] const char* last_error() const noexcept { return last_error_; }

 private:
  struct ModuleState {
    double phi_rad = 0.0;                    // true steering angle
    double psi_rad = 0.0;                    // wheel rotation (what the encoder sees)
    double wheel_rate_radps = 0.0;           // actual wheel rate (after the lag)
    double steer_rate_radps = 0.0;           // actual steering rate of the last sub-step
    double servo_ref_rad = 0.0;              // caster forces: the servo's reference angle
    double servo_rate_radps = 0.0;           // caster forces: its rate (after the steering lag)
    double previous_steer_rate_radps = 0.0;  // caster forces: the sub-step before's
    double slip_state = 0.0;                 // non-systematic slip process
  };
  // Sensor-side state at one instant, kept for the sensor_latency effect.
  struct SensorSample {
    double t_s = 0.0;
    double yaw_rad = 0.0;  // unwrapped
    std::array<double, kMaxModules> psi_rad{};
    std::array<double, kMaxModules> phi_rad{};
  };

  void substep(double h_s, const ActuatorCommand& command) noexcept;
  Twist2 swpc_twist(const ActuatorCommand& command, const double* ground_rate) noexcept;
  // Caster forces: the twist of a sub-step, every module's steering rate set.
  Twist2 caster_force_twist(double h_s, const double* ground_rate) noexcept;
  void record_history() noexcept;
  void sensor_sample_at(double t_s, SensorSample& out) const noexcept;
  static double gaussian(std::mt19937_64& rng) noexcept;
  [[nodiscard]] double quantize(double angle_rad, double counts_per_rev) const noexcept;

  PlantParams plant_;
  SimOptions options_;
  std::size_t n_ = 2;
  double t_s_ = 0.0;
  Pose2 pose_;
  double yaw_unwrapped_rad_ = 0.0;
  Twist2 twist_;
  std::array<ModuleState, kMaxModules> modules_{};
  double scrub_state_ = 0.0;
  std::uint64_t caster_force_failures_ = 0;
  Twist2 previous_twist_;  // caster forces: the sub-step before the last's

  std::mt19937_64 sensor_rng_;
  std::mt19937_64 process_rng_;

  // Motion capture.
  double mocap_period_s_ = 0.01;
  std::uint64_t mocap_next_index_ = 0;
  MotionCaptureSample mocap_pending_;

  // Gyro: the delayed yaw at the previous read, for the mean rate.
  bool have_read_ = false;
  double last_read_t_s_ = 0.0;
  double last_read_yaw_rad_ = 0.0;

  // Ring of past sensor samples (sensor_latency); allocated once.
  std::vector<SensorSample> history_;
  std::size_t history_head_ = 0;  // index of the oldest
  std::size_t history_size_ = 0;
  double history_spacing_s_ = 0.0;

  const char* last_error_ = "";
};

}  // namespace swivel::sim
