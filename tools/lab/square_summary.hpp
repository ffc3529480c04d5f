// SPDX-License-Identifier: Apache-2.0
#pragma once
// The statistics of a Table 5 study (square_study.hpp): each model's end-pose mean absolute
// error with its standard error, the changes against the design values, their spread over
// the calibration seeds, and how well the calibrations recovered the true parameters.

#include <cstddef>
#include <vector>

#include "square_study.hpp"
#include "swivel/stats/summary.hpp"

namespace swivel::lab {

/// End-pose mean absolute errors of one model (or of the mean over calibrated models).
struct EndPoseError {
  stats::Estimate position_m;
  stats::Estimate heading_deg;
};

/// Mean absolute end-pose error over a model's runs: the average of the clockwise and the
/// counter-clockwise means, so that the standard error treats the two directions (whose
/// systematic errors differ) as strata.
EndPoseError end_pose_error(const TrackedModel& tracked);

/// Recovered minus true, root mean square over the calibrations, per module.
struct ModuleAccuracy {
  double position_mm = 0.0;
  double steering_offset_deg = 0.0;
  double caster_offset_mm = 0.0;
  double wheel_radius_mm = 0.0;
};

struct SquareSummary {
  EndPoseError nominal;
  EndPoseError exact;
  /// Mean over the calibrated models; the standard error is that of the K models' errors
  /// (which holds both the calibrations' and the runs' scatter), or of the runs for one.
  EndPoseError calibrated;
  stats::Estimate exact_position_change;  ///< fractions: -0.6 is a 60 % reduction
  stats::Estimate exact_heading_change;
  stats::Estimate position_change;
  stats::Estimate heading_change;
  std::vector<double> seed_position_change;  ///< per calibrated model, against nominal
  std::vector<double> seed_heading_change;
  stats::Summary position_spread;  ///< of seed_position_change
  stats::Summary heading_spread;
  std::size_t position_worse = 0;  ///< models whose change is above zero
  std::size_t heading_worse = 0;
  std::vector<ModuleAccuracy> accuracy;  ///< per module
};

SquareSummary summarize_square(const SquareStudy& study, const RobotModel& truth);

}  // namespace swivel::lab
