// SPDX-License-Identifier: Apache-2.0
#pragma once
// A second robot generator for validating the model-gap workflow, built to differ from
// Swivel's simulator and from tests/independent_robot where it matters: force-based contact
// (creep with saturation, lateral as well as longitudinal), caster steering axes with inertia,
// Coulomb friction and a servo, implicit rigid-body dynamics, motion capture with its own
// latency and a marker offset, its own robots (3, 4 and 6 casters; differential robots of
// other tracks and radii), encoder resolutions, row rates of 20-100 Hz, drive scripts and
// controller. It shares no code with plugins/, tools/model_gap/, tools/lab/ or
// tests/independent_robot and writes its files itself. README.md has the physics.

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace swivel::second {

enum class Drive { kDifferential, kSwpc };

/// One caster module: steering axis position (robot frame), trail and wheel radius.
struct CasterModule {
  double x_m = 0.0;
  double y_m = 0.0;
  double caster_offset_m = 0.0;
  double wheel_radius_m = 0.0;
};

/// A robot as its nominal model states it, plus the physical figures the model has no keys for.
struct Design {
  std::string name;
  Drive drive = Drive::kDifferential;
  double wheel_radius_left_m = 0.0;  ///< differential
  double wheel_radius_right_m = 0.0;
  double track_width_m = 0.0;
  std::vector<CasterModule> modules;  ///< swpc
  double wheel_counts_per_rev = 0.0;
  double steering_counts_per_rev = 0.0;  ///< swpc
  double gyro_noise_rad_s = 0.0;
  double mocap_position_noise_m = 0.0;
  double mocap_yaw_noise_rad = 0.0;
  double mocap_rate_hz = 0.0;
  double linear_accel_limit_mps2 = 0.0;  ///< the robot's own controller, per axis
  double angular_accel_limit_radps2 = 0.0;
  double steering_rate_limit_radps = 0.0;  ///< swpc
  double max_speed_mps = 0.0;              ///< what the drive scripts ask for at most
  double max_yaw_rate_radps = 0.0;
  double mass_kg = 0.0;
  double yaw_inertia_kgm2 = 0.0;
  [[nodiscard]] std::size_t wheel_count() const {
    return drive == Drive::kDifferential ? 2U : modules.size();
  }
};

/// The robots: "trike3", "cart4", "hex6" (swpc) and "mini_diff", "wide_diff", "mid_diff".
std::vector<std::string> design_names();
/// @throws std::invalid_argument naming the known designs.
Design design(const std::string& name);

/// What the true robot is. Library effects (the workflow's names) first, at identity values
/// for the nominal robot; then physics the library has no name for; then the motion capture's
/// own mounting and timing, which the workflow fits as nuisances and never names.
struct Truth {
  double gyro_bias_rad_s = 0.0;
  double gyro_scale = 1.0;
  std::vector<double> wheel_radius_scale;   ///< per wheel (differential: left, right); empty: 1
  double track_width_scale = 1.0;           ///< differential
  std::vector<double> caster_offset_scale;  ///< per module; empty: 1
  std::vector<double> steering_offset_rad;  ///< per module, added to the nominal 0
  double sensor_delay_s = 0.0;              ///< encoders and gyro report the state of then
  double actuator_lag_s = 0.0;              ///< wheel and steering rate setpoints lag
  double steering_lag_s = 0.0;              ///< swpc: steering setpoints only (replaces the above)
  double steering_rate_limit_radps = 0.0;   ///< the robot's clamp; 0: the design's
  double linear_accel_limit_mps2 = 0.0;     ///< the robot's controller; 0: the design's
  double angular_accel_limit_radps2 = 0.0;
  // Outside the library.
  double tyre_stiffness_per_load = 400.0;  ///< creep stiffness, newtons per unit slip per newton
  double friction_coefficient = 0.9;       ///< saturation of the contact force
  double steering_friction_nm = 0.01;      ///< Coulomb friction of each steering axis
  // Motion capture: its own latency and where the tracked body sits on the robot.
  double mocap_latency_s = 0.0;
  /// The motion capture's clock runs this much faster than the robot's (s/s, 0..0.01): a
  /// frame at t shows the robot at t - latency - rate * t, as a log synchronised by hand at
  /// its start and end is.
  double mocap_clock_rate = 0.0;
  double marker_x_m = 0.0;  ///< lever arm, robot frame
  double marker_y_m = 0.0;
  double marker_yaw_rad = 0.0;
};

/// The gear ratio of ModelStatement::fractional_counts.
inline constexpr double kFractionalGear = 1.37;

/// What the nominal model file states under `limits:`.
struct ModelStatement {
  bool accel_limits = true;
  bool steering_rate_limit = true;  ///< swpc
  /// Counts per revolution written as the real numbers of a geared encoder (the design's
  /// counts times 1.37); off until the robot model reads real-valued counts.
  bool fractional_counts = false;
};

enum class Script {
  kWaypoints,  ///< random waypoints, turn then drive (differential) or drive while turning
  kCircles,    ///< circles of several radii, both ways
  kSpotTurns,  ///< turns on the spot with short drives between
  kMixed,      ///< a random mixture of the three
};
const char* script_name(Script s);

struct RunSpec {
  std::string design = "cart4";
  Truth truth;
  ModelStatement model;
  Script script = Script::kMixed;
  double row_rate_hz = 50.0;  ///< 20 to 100
  double duration_s = 90.0;
  std::uint64_t seed = 1;
  bool noise = true;
};

/// One library effect the workflow should name, with every parameter (workflow key names;
/// limits under the effect names `accel_limit` and `steering_rate_limit`).
struct ExpectedEffect {
  std::string effect;
  std::vector<std::pair<std::string, double>> params;
};

/// The library effects in which the true robot differs from what its model states.
std::vector<ExpectedEffect> expected_effects(const RunSpec& spec);

struct GeneratedRun {
  std::string run_csv;
  std::string nominal_model_yaml;
  std::vector<ExpectedEffect> expected;
  /// The generator's own state at each row, which the run log does not show (a CSV: t, the
  /// true pose and body twist, each wheel's true angle and contact speed, and on swpc each
  /// caster's true steering angle and servo error): for tracing what a finding is due to.
  std::string hidden_csv;
  /// largest_driving_servo_error_rad() of the run's rows (0 on a differential robot).
  double driving_servo_error_rad = 0.0;
};

/// Simulates and writes both files. Deterministic per spec.
/// @throws std::invalid_argument naming a bad field of the spec.
GeneratedRun generate(const RunSpec& spec);

/// Sets a truth field from "NAME.PARAM=VALUE" in the workflow's effect names (e.g.
/// "wheel_radius.module_2_scale=1.01", "accel_limit.linear_mps2=0.3") or the generator's own
/// (e.g. "tyre.stiffness_per_load=20", "mocap.latency_s=0.01", "mocap.marker_x_m=0.05").
/// @throws std::invalid_argument naming the problem.
void set_truth(RunSpec& spec, const std::string& assignment);

// The simulated record, for tests: rows as written, with the truth beside them.
struct Row {
  double t_s = 0.0;
  double cmd[3] = {0, 0, 0};
  std::vector<double> wheel_rad;  ///< encoder readings
  std::vector<double> steer_rad;  ///< swpc, wrapped to (-pi, pi]
  double gyro_radps = 0.0;
  bool has_mocap = false;
  double mocap[3] = {0, 0, 0};
  // Truth at t (not written).
  double pose[3] = {0, 0, 0};
  double twist[3] = {0, 0, 0};                   ///< body frame
  std::vector<double> true_wheel_rad;            ///< wheel angles
  std::vector<double> true_steer_rad;            ///< true steering angles (unwrapped)
  std::vector<double> contact_speed_mps;         ///< ground speed of each contact along its heading
  std::vector<double> contact_travel_m;          ///< its integral since the start
  std::vector<double> steering_servo_error_rad;  ///< swpc: servo reference minus true angle
};
std::vector<Row> simulate(const RunSpec& spec);

/// How far the body's motion over each second of `b` departs from `a`'s (the same commands),
/// in the body frame at the second's start, summed over the run, per metre of `a`'s path.
double motion_apart_per_metre(const std::vector<Row>& a, const std::vector<Row>& b,
                              double row_rate_hz);

/// What a run's drivetrain geometry (wheel radii, track width, caster offsets, steering
/// offsets) moves the body by, against the same run on the nominal geometry, with no noise:
/// motion_apart_per_metre() with the truth's deviations as they are and halved.
///
/// A geometry the wheels roll by moves the body in proportion to it (growth 2). One wheel or
/// caster off on an over-actuated robot whose stiff tyres hold it skids instead: its friction
/// limit, not its size, sets what the body shows (growth near 1), and no log of the run carries
/// the size.
struct GeometryFootprint {
  double full = 0.0;
  double half = 0.0;
  /// full / half (NaN when the halved geometry moves nothing).
  [[nodiscard]] double growth() const {
    return half > 0.0 ? full / half : std::numeric_limits<double>::quiet_NaN();
  }
  /// The body shows the size when halving it takes away at least a quarter of its footprint
  /// (growth >= 4/3): a rolling geometry gives 2, one wheel or caster skidding 1.0-1.25. Near
  /// the friction limit (a hex6 wheel 1 % large: 1.4) the halved size still rolls in part.
  [[nodiscard]] bool size_in_motion() const { return growth() >= kMinFootprintGrowth; }
  static constexpr double kMinFootprintGrowth = 4.0 / 3.0;
};

/// nullopt when the truth's geometry is the nominal robot's. Three simulations of the run.
std::optional<GeometryFootprint> geometry_footprint(const RunSpec& spec);

/// Rows whose body moves faster than this count as driving (driving_servo_errors_rad()).
inline constexpr double kDrivingSpeedMps = 0.1;

/// Per caster, the median |servo error| (reference minus true angle) over the rows where the
/// body drives: how hard the steering servos press against the tyres. Anything that sets the
/// controller's caster law apart from the body's motion (a steering offset or a sensor latency
/// it does not know, say) winds each servo's reference on until the servo drags its tyre
/// sideways at the friction limit d mu load / Kp, where the error stays while the robot drives
/// and from which the caster lets go at the stops. Empty for a differential robot; 0 for a
/// caster that never drives.
std::vector<double> driving_servo_errors_rad(const std::vector<Row>& rows);

/// Per caster, the servo error at which its tyre slides: d mu load / Kp, the trail, tyre
/// friction and load of the true robot over its servo's stiffness. Empty for a differential
/// robot.
std::vector<double> friction_limit_servo_errors_rad(const RunSpec& spec);

/// The largest of driving_servo_errors_rad() (0 for a differential robot).
double largest_driving_servo_error_rad(const std::vector<Row>& rows);

/// A run whose largest driving servo error reaches this has servos fighting their tyres.
/// Read off the fifth validation set's 40 caster runs with a hidden effect: their largest
/// medians fall at 0.2-4.7 mrad or at 6.6-54 mrad, nothing between (clean runs 0.3-0.8).
inline constexpr double kFightingServoErrorRad = 0.005;

}  // namespace swivel::second
