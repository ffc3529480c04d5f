// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/run_data.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "swivel/model_gap/run_log_adapter.hpp"
#include "swivel/run_log.hpp"

namespace swivel::model_gap {

RunData to_run_data(const RunLog& log) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  RunData d;
  d.source = log.source;
  d.drivetrain = log.header.drivetrain;
  d.module_count = log.header.module_count;
  d.gyro_mean_over_row = log.header.gyro_mean_over_row;
  const std::size_t n = log.samples.size();
  d.t_s.reserve(n);
  d.cmd_vx_mps.reserve(n);
  d.cmd_vy_mps.reserve(n);
  d.cmd_wz_radps.reserve(n);
  d.wheel_rad.assign(d.module_count, {});
  if (d.drivetrain == DrivetrainKind::kSwpc) d.steer_rad.assign(d.module_count, {});
  for (const RunLogSample& s : log.samples) {
    d.t_s.push_back(s.t_s);
    d.cmd_vx_mps.push_back(s.cmd.vx_mps);
    d.cmd_vy_mps.push_back(s.cmd.vy_mps);
    d.cmd_wz_radps.push_back(s.cmd.wz_radps);
    for (std::size_t i = 0; i < d.module_count; ++i) {
      d.wheel_rad[i].push_back(s.wheel_rad[i]);
      if (!d.steer_rad.empty()) d.steer_rad[i].push_back(s.steer_rad[i]);
    }
    d.gyro_radps.push_back(s.gyro_wz_radps);
    d.truth_x_m.push_back(s.has_truth ? s.truth.x_m : kNaN);
    d.truth_y_m.push_back(s.has_truth ? s.truth.y_m : kNaN);
    d.truth_yaw_rad.push_back(s.has_truth ? s.truth.yaw_rad : kNaN);
  }
  // Motion capture reports a wrapped heading; unwrapped it interpolates and plots cleanly.
  double offset = 0.0;
  double previous = kNaN;
  for (double& yaw : d.truth_yaw_rad) {
    if (!std::isfinite(yaw)) continue;
    if (std::isfinite(previous)) {
      const double jump = yaw + offset - previous;
      offset -= 2.0 * std::numbers::pi * std::round(jump / (2.0 * std::numbers::pi));
    }
    yaw += offset;
    previous = yaw;
  }
  return d;
}

RunData load_run(const std::string& path) { return to_run_data(read_run_log(path)); }

}  // namespace swivel::model_gap
