// SPDX-License-Identifier: Apache-2.0
#pragma once
// Everything that defines one generated run: which robot, what it truly is (the library
// effects and the effects outside the library), the noise, the tour and the seed. The
// generator is a function of this value alone.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace swivel::independent {

/// Wheels (docent: left, right) or modules (swpc4) at most.
inline constexpr std::size_t kMaxWheels = 4;

enum class Robot { kDocent, kSwpc4 };

/// How the swpc4 steering moves: driven by its motors, or passive (the casters trail).
enum class Steering { kPowered, kSelfAligning };

/// What the nominal model file states under `limits:`.
enum class ModelLimits {
  kAll,           ///< acceleration limits and (swpc4) the steering rate limit
  kSteeringOnly,  ///< swpc4: the steering rate limit only; docent: nothing
  kNone,          ///< no `limits:` section
};

/// Body twist, robot frame (x forward, y left), yaw counter-clockwise.
struct Twist {
  double vx_mps = 0.0;
  double vy_mps = 0.0;
  double wz_radps = 0.0;
};

/// Planar pose in the motion-capture (world) frame.
struct Pose {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

/// The true robot in the model-gap library's terms: identity values mean "as the nominal
/// model says". Per-wheel arrays: docent [0] left, [1] right; swpc4 modules 1..4.
struct TrueEffects {
  double gyro_bias_rad_s = 0.0;                                            ///< gyro_bias.bias_rad_s
  double gyro_scale = 1.0;                                                 ///< gyro_scale.scale
  std::array<double, kMaxWheels> wheel_radius_scale{1.0, 1.0, 1.0, 1.0};   ///< wheel_radius
  double track_width_scale = 1.0;                                          ///< track_width.scale
  std::array<double, kMaxWheels> caster_offset_scale{1.0, 1.0, 1.0, 1.0};  ///< caster_offset
  std::array<double, kMaxWheels> steering_offset_rad{};  ///< steering_offset, added
  double sensor_delay_s = 0.0;                           ///< sensor_latency.delay_s
  double actuator_time_constant_s = 0.0;                 ///< actuator_lag.time_constant_s
  double steering_time_constant_s = 0.0;                 ///< steering_lag.time_constant_s (swpc4)
  double steering_rate_limit_radps = 6.0;  ///< what the robot clamps steering rates to
  double linear_accel_limit_mps2 = 0.6;    ///< what the robot's controller enforces
  double angular_accel_limit_radps2 = 2.0;
  double slip_gain_per_radps2 = 0.0;  ///< slip.gain_per_radps2
};

/// Effects the model-gap library has no name for.
struct OutsideEffects {
  double floor_drift_x_mps = 0.0;  ///< the motion-capture frame moves against the floor
  double floor_drift_y_mps = 0.0;
  double dropped_counts_interval_s = 0.0;  ///< mean time between lost-count bursts; 0: none
  int dropped_counts_min = 5;              ///< counts lost in one burst, uniform in [min, max]
  int dropped_counts_max = 50;
  int eccentric_wheel = 0;           ///< 1-based wheel (docent 1 left, 2 right); 0: none
  double eccentric_amplitude = 0.0;  ///< effective radius r (1 + a cos psi)
  double gyro_drift_rad_s = 0.0;     ///< bias runs linearly from -x at t = 0 to +x at the end
};

/// Noise and timing of the measurement. `quiet()` turns every random part off.
struct NoiseSpec {
  double slip_std = 0.002;          ///< wheel slip ratio, stationary standard deviation
  double slip_correlation_s = 5.0;  ///< its correlation time (Ornstein-Uhlenbeck)
  double gyro_noise_rad_s = 0.002;  ///< white, per row
  double mocap_position_noise_m = 0.0003;
  double mocap_yaw_noise_rad = 0.001;
  double mocap_rate_hz = 100.0;      ///< frames on the motion-capture system's own clock
  double mocap_clock_ppm = 30.0;     ///< how much faster that clock runs than the robot's
  double mocap_dropout = 0.005;      ///< share of frames lost (occlusions)
  double row_rate_hz = 100.0;        ///< nominal log rate
  double row_jitter_s = 0.0003;      ///< sample-time jitter, standard deviation ...
  double row_jitter_clip_s = 0.001;  ///< ... clipped to this

  /// No slip, no sensor noise, no dropouts, no jitter: for closed-form checks.
  static NoiseSpec quiet();
};

/// One step of a tour: from `start_s` the setpoint moves linearly (over `ramp_s`, 0 for a
/// step) from the previous segment's target to `target`, then holds it.
struct TourSegment {
  double start_s = 0.0;
  double ramp_s = 0.0;
  Twist target;
};

struct RunSpec {
  Robot robot = Robot::kDocent;
  Steering steering = Steering::kPowered;  ///< swpc4 only
  double duration_s = 120.0;
  std::uint64_t seed = 1;  ///< tour, start pose and every noise stream
  TrueEffects truth;
  OutsideEffects outside;
  NoiseSpec noise;
  ModelLimits model_limits = ModelLimits::kAll;
  std::vector<TourSegment> tour;   ///< empty: the standard tour of this robot and seed
  std::optional<Pose> start_pose;  ///< empty: drawn from the seed
};

/// "docent" or "swpc4".
std::string robot_name(Robot robot);

/// Wheels (docent) or modules (swpc4).
std::size_t wheel_count(Robot robot);

/// Checks a spec before generation.
/// @throws std::invalid_argument naming the field and the accepted range.
void validate(const RunSpec& spec);

}  // namespace swivel::independent
