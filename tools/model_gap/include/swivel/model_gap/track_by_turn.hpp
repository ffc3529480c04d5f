// SPDX-License-Identifier: Apache-2.0
#pragma once
// A left/right wheel-radius difference, from the tracks runs fixed alone while turning at
// different radii (tools/lab/GAP.md section 8, "Circles both ways").
//
// On a circle of radius R (signed: positive turning left) a differential robot whose right
// wheel is (1 + e) and left wheel (1 - e) of the radius its odometry assumes turns by an extra
// 2 e v / b, which a track fitted alone takes up as s = s0 - 2 e R / b: one circle cannot tell
// the two apart, circles both ways round can. Turns on the spot (R = 0) fix s0 alone.

#include <cstddef>
#include <vector>

#include "swivel/model_gap/run_data.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::model_gap {

/// The radius a run's turning is done at, as a track-width fit weighs it: over windows of
/// `window_s`, sum(distance x heading change) / sum(heading change^2), both from the nominal
/// odometry (m; 0 for turns on the spot, R on a circle of radius R turning left, -R turning
/// right; NaN for a run that does not turn or is not differential).
double turn_radius_m(const RobotModel& nominal, const RunData& run, double window_s);

/// Tracks fitted alone (scales on the nominal track) against the radius each run turned at.
struct TrackByTurn {
  bool fitted = false;  ///< false: fewer than two runs turning each way (then s0 alone)
  double track_scale = 0.0;
  double track_scale_sigma = 0.0;
  double radius_difference = 0.0;  ///< e: right wheel (1 + e), left (1 - e) of nominal
  double radius_difference_sigma = 0.0;
  double chi_square = 0.0;            ///< of the runs about the fitted line
  double chi_square_one_track = 0.0;  ///< of the same runs about their weighted mean
  std::size_t runs = 0;
};

/// Runs that turned less than this radius either way count as turning that way (m).
inline constexpr double kMinTurnRadiusEachWayM = 0.05;

/// Weighted least squares of `scales` (sigmas `sigmas`) on the runs' `radii_m`.
TrackByTurn fit_track_by_turn(const std::vector<double>& scales, const std::vector<double>& sigmas,
                              const std::vector<double>& radii_m, double track_width_m);

}  // namespace swivel::model_gap
