// SPDX-License-Identifier: Apache-2.0
#pragma once
// Windows of a run: consecutive stretches of about a second over which measured and
// predicted changes are compared. Comparing changes instead of values whitens the noise of
// integrated channels: the heading a dead reckoning has accumulated, or the drift of a
// randomly slipping wheel, cancels out of each window, and what remains is nearly
// independent from window to window.
//
// Each window starts and ends on a row with motion capture (when the run has any). The
// pose there is the motion capture's, its noise averaged over the neighbouring rows with
// the dead-reckoned path as the local shape (anchors()).

#include <cstddef>
#include <vector>

#include "swivel/model_gap/run_data.hpp"
#include "swivel/types.hpp"

namespace swivel::model_gap {

/// Rows [a, b] (a < b).
struct Window {
  std::size_t a = 0;
  std::size_t b = 0;
};

/// Consecutive windows of at least `length_s` covering [first_s, last_s] of the run. With
/// motion capture, both ends lie on rows that have it, and a gap in it longer than
/// 2 length_s starts a new chain of windows after the gap.
std::vector<Window> make_windows(const RunData& run, double length_s, double first_s,
                                 double last_s);

/// What the robot did in each window, from the measured encoders and the commands: the
/// regressors of the noise model and of the misfit tests.
struct WindowMotion {
  std::vector<double> start_s;
  std::vector<double> duration_s;
  std::vector<double> wheel_travel_rad;  ///< mean over wheels of |wheel rotation|
  std::vector<double> steer_travel_rad;  ///< mean over modules of |steering rotation| (swpc)
  std::vector<double> accel_mps2;        ///< mean |commanded body acceleration|, m/s^2
  std::vector<double> angular_accel_radps2;
  std::vector<double> start_yaw_rad;  ///< world heading at the window's start (motion capture)
  /// Per module: sin and cos of the wheel angle at the window's end minus at its start.
  std::vector<std::vector<double>> wheel_sin_change;
  std::vector<std::vector<double>> wheel_cos_change;
};

WindowMotion window_motion(const RunData& run, const std::vector<Window>& windows);

/// Per caster module of `model` and window (MisfitInputs::slowest_roll_offsets): the slowest
/// commanded speed of the module's steering axis in the window times its length, over the
/// caster offset. Empty for a differential robot or a run without commands.
std::vector<std::vector<double>> slowest_roll_offsets(const RunData& run,
                                                      const std::vector<Window>& windows,
                                                      const RobotModel& model);

/// Motion-capture pose at row `row`, its noise averaged over the rows within
/// `half_width` rows that have motion capture: the offset between motion capture and the
/// dead-reckoned path `shape` (any frame, one pose per row, unwrapped heading) is averaged
/// and added back to the path at `row`. NaN pose when `row` has no motion capture.
Pose2 anchor(const RunData& run, const std::vector<Pose2>& shape, std::size_t row,
             std::size_t half_width);

}  // namespace swivel::model_gap
