// SPDX-License-Identifier: Apache-2.0
#pragma once
// Monte Carlo check of the calibration (the paper's Table 3): random true parameters around
// a design, the exact calibration motion, calibration, mean absolute errors.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "swivel/calibration/calibration_motion.hpp"
#include "swivel/calibration/swpc_calibration.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::calibration {

/// The paper's uncalibrated 4-module design (docs/methods.md §1): axes at (+-215, +-125) mm,
/// delta 0, d 20 mm, r 55 mm.
std::vector<SwpcModuleParams> paper_design_modules();

/// The paper's calibrated values of its real robot (docs/methods.md §1, Table 4), in metres and
/// radians: a true robot unlike the design, for simulations (config/robots/swpc4_table4.yaml
/// holds the same values).
std::vector<SwpcModuleParams> paper_table4_modules();

struct MonteCarloOptions {
  std::size_t trials = 10000;
  std::uint64_t seed = 1;
  std::vector<SwpcModuleParams> design = paper_design_modules();
  /// x, y, d and r drawn uniformly within design * (1 +- relative_spread).
  double relative_spread = 0.3;
  /// delta drawn uniformly within +- this, rad (30 deg).
  double steering_offset_spread_rad = 0.5235987755982988;
  /// Locked angles, rotation, sampling and motion-capture noise. The start pose is drawn
  /// per trial (position within +-2 m, any heading).
  CalibrationMotionOptions motion;
  CalibrationOptions calibration;
  /// Called after every trial with (trials done, total); may be empty.
  std::function<void(std::size_t, std::size_t)> progress;
};

/// Mean absolute errors over the modules of one trial: the trials are the independent
/// draws, so the standard errors of the MAEs come from these.
struct TrialErrors {
  double position_m = 0.0;
  double steering_offset_rad = 0.0;
  double caster_offset_m = 0.0;
  double wheel_radius_m = 0.0;
};

struct MonteCarloResult {
  std::size_t trials = 0;
  std::size_t refused = 0;         ///< trials whose calibration refused (excluded from errors)
  std::string first_refusal;       ///< reason of the first refusal, for the report
  std::size_t module_samples = 0;  ///< calibrated modules the errors average over
  /// Mean absolute errors over all calibrated modules of all accepted trials. Position is the
  /// Euclidean distance between the estimated and true steering axis.
  double mae_position_m = 0.0;
  double mae_steering_offset_rad = 0.0;
  double mae_caster_offset_m = 0.0;
  double mae_wheel_radius_m = 0.0;
  double max_position_m = 0.0;
  double max_steering_offset_rad = 0.0;
  double max_caster_offset_m = 0.0;
  double max_wheel_radius_m = 0.0;
  std::vector<TrialErrors> trial_errors;  ///< one per accepted trial
  /// Fraction of per-coordinate errors (x, y, delta, d, r) within 3 reported sigma; only
  /// meaningful with noise (noise-free sigmas are rounding-level).
  double coverage_3sigma = 0.0;
  double wall_s = 0.0;       ///< whole run
  double calibrate_s = 0.0;  ///< time inside calibrate() only
};

/// Runs the Monte Carlo. Deterministic for a given seed (each trial has its own stream).
MonteCarloResult run_monte_carlo(const MonteCarloOptions& options);

}  // namespace swivel::calibration
