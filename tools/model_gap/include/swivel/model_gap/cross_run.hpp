// SPDX-License-Identifier: Apache-2.0
#pragma once
// Cross-run evidence (tools/lab/GAP.md "Across runs"): a model fitted on one run of a robot is
// judged on the robot's other runs. For every run in turn, the sensor-to-pose question names
// what that run shows (or, naming nothing, calibrates the robot model's own parameters it
// fixes); the fitted model is then replayed on each other run beside the nominal
// one, each with that run's own motion-capture nuisances fitted (they belong to the set-up, not
// the robot), and the whole-run RMS position gap of the two is compared. Independently, the
// values each run named or calibrated are checked for agreement across runs within their stated
// sigmas. Runs are judged only on runs of their own session: the folder their file is in (a
// session's set-up, motion capture and floor are its own).

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "swivel/model_gap/run_data.hpp"
#include "swivel/model_gap/track_by_turn.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::model_gap {

/// The median of `values` (NaN when there are none).
double median(std::vector<double> values);

/// The sensor-to-pose gap of one run under one model, with the run's motion-capture nuisances
/// fitted for that model.
struct HeldOutGap {
  std::string run;
  double rms_position_m = 0.0;
  double rms_heading_rad = 0.0;
};

/// Fits the motion-capture nuisances of `run` under `model` alone (no candidate effects) and
/// returns the whole-run gap of its dead reckoning.
/// @throws std::invalid_argument as analyse_gap for a run that does not fit the model or is
///         too short.
HeldOutGap held_out_gap(const RobotModel& model, const RunData& run, const GapOptions& options);

/// One run used to fit, and what its model does on the others.
struct FitRun {
  std::string run;
  Verdict verdict = Verdict::kNoSignificantGap;
  std::string summary;
  std::vector<FittedEffect> named;       ///< sensor to pose
  std::vector<FittedEffect> calibrated;  ///< sensor to pose, when it named nothing
  std::vector<std::string> truth;        ///< its motion-capture nuisances, in words
  RobotModel fitted;                     ///< the nominal model with what it named or calibrated
  /// The radius its turning was done at (turn_radius_m; NaN: not differential or no turning).
  double turn_radius_m = 0.0;
  /// Per other run: nominal and fitted gap (RMS position), and their ratio fitted / nominal.
  std::vector<std::string> others;
  std::vector<double> nominal_rms_m;
  std::vector<double> fitted_rms_m;
  std::vector<double> ratio;
};

/// One parameter across the runs that named or calibrated it.
struct ParameterAgreement {
  std::string name;  ///< "effect.key"
  std::vector<std::string> runs;
  std::vector<double> values;
  std::vector<double> sigmas;
  double weighted_mean = 0.0;
  double sigma_of_mean = 0.0;
  double chi_square = 0.0;  ///< of the values about their weighted mean
  std::size_t dof = 0;
  /// Share of runs whose value lies within 1 (2) stated sigmas of the weighted mean of the
  /// others.
  double within_1_sigma = 0.0;
  double within_2_sigma = 0.0;
};

struct CrossRunResult {
  std::vector<FitRun> fits;
  std::vector<std::string> skipped;  ///< "run: reason" (too short, no motion capture, ...)
  std::vector<ParameterAgreement> agreement;
  double median_ratio = 0.0;  ///< over every (fit run, other run) pair
  std::size_t pairs = 0;
  /// Over the pairs whose fit run named or calibrated something (the others predict exactly
  /// as the nominal model does, ratio 1), and their whole-run RMS position gaps, nominal and
  /// fitted.
  double median_ratio_named = 0.0;
  std::size_t pairs_named = 0;
  double median_nominal_rms_m = 0.0;
  double median_fitted_rms_m = 0.0;
  std::size_t named = 0;        ///< sensor verdicts "named"
  std::size_t no_gap = 0;       ///< sensor verdicts "no significant gap"
  std::size_t calibrated = 0;   ///< of those, runs that calibrated a parameter
  std::size_t unexplained = 0;  ///< sensor verdicts "unexplained residual"
  /// The model fitted on all the runs together: the nominal one with the set of effects most
  /// runs named or calibrated (two at least; runs that fixed another set fitted beside other
  /// effects, and pooling across sets would count an effect twice), each parameter at its
  /// weighted mean over those runs. Written, folded, as DIR/model_pooled.yaml.
  RobotModel pooled;
  /// When the pooled set is a track alone, on runs that turned both ways round: the track
  /// and the left/right radius difference it holds (track_by_turn.hpp). Pooled as such when
  /// the difference is significant at the calibration's level (QuestionOptions::
  /// min_z_calibrate); the pooled track is then its s0.
  TrackByTurn track_by_turn;
  std::vector<std::string> pooled_from;      ///< "track_width.scale = 1.0127 +- 0.00028 (49 runs)"
  std::vector<std::string> pooled_left_out;  ///< "track_width+wheel_radius: 1 run, not the ..."
};

/// Progress of a long cross-run analysis: (step done, steps in all, what).
using CrossRunProgress = std::function<void(std::size_t, std::size_t, const std::string&)>;

/// Fits on each run and validates on the others (every run of `runs` is of one robot).
CrossRunResult cross_validate(const RobotModel& nominal, const std::vector<RunData>& runs,
                              const GapOptions& options, const CrossRunProgress& progress = {});

/// Writes DIR/cross_run.md, DIR/cross_run.json and DIR/model_pooled.yaml. Creates DIR.
/// @throws std::runtime_error when a file cannot be written.
void write_cross_run_report(const CrossRunResult& result, const RobotModel& nominal,
                            const std::string& dir);

}  // namespace swivel::model_gap
