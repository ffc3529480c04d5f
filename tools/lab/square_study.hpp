// SPDX-License-Identifier: Apache-2.0
#pragma once
// The Table 5 study of docs/methods.md §1 with its statistics: the simulated robot (true model:
// the paper's Table 4) tracks the square with the design values, with the true values
// themselves (the best any calibration could give), and with the values each of K
// simulated calibrations recovers, N runs per direction each. Every run and every
// calibration has its own seed, derived from one base seed, so the K models and the runs
// are independent draws and the result does not depend on how many jobs ran them.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "square_experiment.hpp"
#include "swivel/calibration/simulated_procedure.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::lab {

struct SquareStudyOptions {
  int calibration_seeds = 20;   ///< K simulated calibrations
  int runs_per_direction = 20;  ///< N square runs per direction for every model
  std::uint64_t seed = 1;
  /// Laps, speed, non-systematic errors, integration step; seed, direction and trace are
  /// set per run.
  SquareRunOptions run;
  /// The simulated calibration (the daemon's procedure); the world's seed is set per
  /// calibration.
  calibration::SimulatedProcedureOptions calibration;
  /// Given: tracked as the only calibrated model, and no calibration is simulated.
  std::optional<RobotModel> calibrated_model;
  int traced_runs = 4;  ///< per direction, traced for the plot (nominal, exact, first model)
  int jobs = 1;         ///< threads
};

struct TrackedRun {
  bool counter_clockwise = true;
  int index = 0;  ///< 0-based within its direction
  std::uint64_t seed = 0;
  double position_error_m = 0.0;   ///< |true end - commanded end|
  double heading_error_deg = 0.0;  ///< |true end yaw - commanded end yaw|
  std::vector<Pose2> trace;        ///< true poses (traced runs only)
};

struct TrackedModel {
  RobotModel model;
  std::vector<TrackedRun> runs;  ///< clockwise runs, then counter-clockwise
};

struct CalibratedModel {
  std::uint64_t calibration_seed = 0;   ///< of the world; 0 for a given model
  double calibration_duration_s = 0.0;  ///< simulated time of the procedure
  TrackedModel tracked;
};

struct SquareStudy {
  TrackedModel nominal;
  TrackedModel exact;
  std::vector<CalibratedModel> calibrated;
};

/// Called after each model has been tracked, from the job that tracked it, one call at a
/// time: models done, models in all, and what was done.
using StudyProgress = std::function<void(int done, int total, const std::string& what)>;

/// Runs the study. @throws std::runtime_error when a simulated calibration is refused or a
/// run does not finish; what the jobs throw otherwise.
SquareStudy run_square_study(const RobotModel& nominal, const RobotModel& truth,
                             const SquareStudyOptions& options, const StudyProgress& progress);

}  // namespace swivel::lab
