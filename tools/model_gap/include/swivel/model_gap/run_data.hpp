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
  std::vector<double> t_s;
  std::vector<double> cmd_vx_mps;
  std::vector<double> cmd_vy_mps;
  std::vector<double> cmd_wz_radps;
  std::vector<std::vector<double>> wheel_rad;  ///< [module][sample], cumulative
  std::vector<std::vector<double>> steer_rad;  ///< [module][sample], swpc only
  std::vector<double> gyro_radps;
  std::vector<double> truth_x_m;  ///< NaN where there is no motion-capture sample
  std::vector<double> truth_y_m;
  std::vector<double> truth_yaw_rad;

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
