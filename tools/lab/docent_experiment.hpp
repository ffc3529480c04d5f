// SPDX-License-Identifier: Apache-2.0
#pragma once
// The docent paper's experiment (docs/methods.md §2) in simulation: straight runs along the
// corridor lines S1 and S2 on a docent robot whose true sensors and wheels differ from the
// nominal model by drawn, stated errors, localized by E/G, LCAKF, LCALSM (paper and
// heading_aligned) and the pose EKF, all from the same encoder and gyro readings.
// Used by `swivel-lab reproduce docent`. Not real-time code.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::lab {

/// The localization methods compared, in table order.
enum class DocentMethod : std::size_t {
  kEg = 0,             ///< E/G dead reckoning (gyro heading)
  kLcakf = 1,          ///< kalman mode lcakf
  kLcalsmPaper = 2,    ///< lsm mode paper (the faithful LCALSM)
  kLcalsmHeading = 3,  ///< lsm mode heading_aligned (variant, extra column)
  kEkf = 4,            ///< kalman mode ekf (extra column)
};
inline constexpr std::size_t kDocentMethodCount = 5;

/// Short column label ("E/G", "LCAKF", ...).
const char* docent_method_label(DocentMethod m);
/// Key used in results.json ("eg", "lcakf", ...).
const char* docent_method_key(DocentMethod m);

struct DocentScenario {
  std::string name;  ///< "S1"
  double start_x_m = 0.0;
  double line_y_m = 0.0;
  double end_x_m = 0.0;
};

/// The paper's two scenarios in the 8 m x 10 m corridor.
std::vector<DocentScenario> docent_scenarios();

/// Ranges from which each run's true robot is drawn, and the fixed error sources.
struct DocentErrorModel {
  double gyro_bias_sigma_radps = 3.5e-4;  ///< residual bias after start-up calibration (0.02 deg/s)
  double gyro_scale_sigma = 0.005;        ///< scale factor error, 1-sigma
  double gyro_noise_radps = 0.002;        ///< white noise per 100 Hz sample, 1-sigma
  double wheel_radius_error_max = 0.003;  ///< each true radius = nominal (1 + U(-max, max))
  double wheel_slip_std = 0.003;          ///< random slip, relative 1-sigma (Gauss-Markov)
  double slip_correlation_time_s = 0.5;
};

/// How the robot is driven.
struct DocentDriveProfile {
  double rate_hz = 100.0;       ///< control, sensor and localization rate
  double still_before_s = 2.0;  ///< standing still before moving (gyro running)
  double cruise_speed_mps = 0.3;
  double accel_mps2 = 0.3;            ///< ramp up and braking to the end point
  double min_speed_mps = 0.02;        ///< creep speed for the last millimetres
  double lateral_gain_per_m2 = 11.0;  ///< line follower: wz = -(k_lat v e + k_yaw yaw)
  double yaw_gain_per_s = 1.4;
};

struct DocentExperimentConfig {
  std::size_t runs = 5;
  std::uint64_t seed = 1;
  double sample_spacing_m = 0.1;  ///< errors sampled where the truth crosses every spacing
  DocentErrorModel errors;
  DocentDriveProfile drive;
  bool keep_trace = true;  ///< keep run 1's decimated trajectory per scenario
  double trace_period_s = 0.1;
};

/// What was drawn for one run (the true robot).
struct DocentRunDraw {
  std::uint64_t seed = 0;
  double gyro_bias_radps = 0.0;
  double gyro_scale = 1.0;
  double wheel_radius_scale_left = 1.0;
  double wheel_radius_scale_right = 1.0;
};

/// One pose per method plus the truth.
struct DocentTracePoint {
  double t_s = 0.0;
  Pose2 truth;
  std::array<Pose2, kDocentMethodCount> estimate{};
};

struct DocentMethodStats {
  double max_error_m = 0.0;
  double mean_error_m = 0.0;
  double std_error_m = 0.0;  ///< over the run's samples (population)
  /// Largest distance between the method's own E/G input and the reference E/G over the
  /// run; zero when every method is fed from identical E/G positions.
  double eg_input_mismatch_m = 0.0;
};

struct DocentRunResult {
  DocentRunDraw draw;
  std::vector<double> sample_x_m;                                ///< true x at each sample
  std::array<std::vector<double>, kDocentMethodCount> errors_m;  ///< per sample
  std::array<DocentMethodStats, kDocentMethodCount> stats{};
  double duration_s = 0.0;
  Pose2 true_end;
  double ekf_bias_radps = 0.0;          ///< the EKF's gyro-bias estimate at the end
  std::vector<DocentTracePoint> trace;  ///< empty unless kept
};

struct DocentScenarioResult {
  DocentScenario scenario;
  std::vector<DocentRunResult> runs;
};

/// Draws run `run` (0-based) of scenario `scenario_index`; depends only on the three numbers.
DocentRunDraw draw_docent_run(const DocentErrorModel& errors, std::uint64_t seed,
                              std::size_t scenario_index, std::size_t run);

/// Simulates one run and localizes it with every method.
/// @throws std::invalid_argument for a non-differential model; std::runtime_error when the
///         simulation fails or the run does not reach the end point.
DocentRunResult run_docent(const RobotModel& nominal, const DocentScenario& scenario,
                           const DocentRunDraw& draw, const DocentExperimentConfig& config,
                           bool keep_trace);

/// Every run of every scenario.
std::vector<DocentScenarioResult> run_docent_experiment(const RobotModel& nominal,
                                                        const DocentExperimentConfig& config);

}  // namespace swivel::lab
