// SPDX-License-Identifier: Apache-2.0
#pragma once
// A run (swivel/run_log.hpp) as columns, the shape the replay and the analysis work on.

#include <cstddef>
#include <string>
#include <vector>

#include "swivel/model_gap/locate.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::model_gap {

struct RunData {
  std::string source;  ///< file it came from, for messages
  DrivetrainKind drivetrain = DrivetrainKind::kDifferential;
  std::size_t module_count = 2;  ///< 2 (left, right) for a differential robot
  /// gyro_radps[k] is the mean rate over (t[k-1], t[k]] (the log's `# gyro_wz: mean over the
  /// row`); false: the reading at t[k] (swivel/run_log.hpp).
  bool gyro_mean_over_row = false;
  /// Every row has a gyro sample. A log with no gyro, or mixing rows with and without one, has
  /// false: the workflow treats a run as having a gyro channel only when it is complete.
  bool has_gyro = true;
  /// Every row has a logged command (false as for has_gyro when any row has none).
  bool has_commands = true;
  std::vector<double> t_s;
  std::vector<double> cmd_vx_mps;  ///< NaN where the row has no command
  std::vector<double> cmd_vy_mps;
  std::vector<double> cmd_wz_radps;
  std::vector<std::vector<double>> wheel_rad;  ///< [module][sample], cumulative
  /// [module][sample], swpc only; unwrapped (continuous across +-pi) whatever the log held.
  std::vector<std::vector<double>> steer_rad;
  std::vector<double> gyro_radps;  ///< NaN where the row has no gyro sample
  std::vector<double> truth_x_m;   ///< NaN where there is no motion-capture sample
  std::vector<double> truth_y_m;
  std::vector<double> truth_yaw_rad;
  /// The motion capture is stamped on the robot's own clock (`# truth_clock: shared`, e.g.
  /// a simulator's): its time offset is known to be zero and is not fitted.
  bool truth_clock_shared = false;
  /// The motion capture's clock runs at the robot clock's rate, offset by an unknown constant
  /// (`# truth_clock: same_rate`, e.g. stamped on receipt by a live link): its offset is
  /// fitted, not its rate.
  bool truth_clock_same_rate = false;
  /// The motion capture reports the robot's own reference frame (`# truth_frame: robot`, e.g.
  /// a simulator's truth): the tracked body's offset on the robot is known to be zero.
  bool truth_frame_is_robot = false;

  [[nodiscard]] std::size_t size() const { return t_s.size(); }
  [[nodiscard]] CommandSeries commands() const {
    return {t_s, cmd_vx_mps, cmd_vy_mps, cmd_wz_radps};
  }
};

/// Reads a run log (CSV of swivel/run_log.hpp).
/// @throws RunLogError (a std::runtime_error) naming the file and line for malformed or
/// truncated content.
RunData load_run(const std::string& path);

}  // namespace swivel::model_gap
