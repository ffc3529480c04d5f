// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/run_data.hpp"

#include <cmath>
#include <limits>

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
    d.cmd_vx_mps.push_back(s.has_cmd ? s.cmd.vx_mps : kNaN);
    d.cmd_vy_mps.push_back(s.has_cmd ? s.cmd.vy_mps : kNaN);
    d.cmd_wz_radps.push_back(s.has_cmd ? s.cmd.wz_radps : kNaN);
    d.has_commands = d.has_commands && s.has_cmd;
    for (std::size_t i = 0; i < d.module_count; ++i) {
      d.wheel_rad[i].push_back(s.wheel_rad[i]);
      if (!d.steer_rad.empty()) {
        // Absolute steering encoders wrap to (-pi, pi]; the replays difference these.
        std::vector<double>& steer = d.steer_rad[i];
        double phi = s.steer_rad[i];
        if (!steer.empty()) phi = unwrap_near(phi, steer.back());
        steer.push_back(phi);
      }
    }
    d.gyro_radps.push_back(s.has_gyro ? s.gyro_wz_radps : kNaN);
    d.has_gyro = d.has_gyro && s.has_gyro;
    d.truth_x_m.push_back(s.has_truth ? s.truth.x_m : kNaN);
    d.truth_y_m.push_back(s.has_truth ? s.truth.y_m : kNaN);
    d.truth_yaw_rad.push_back(s.has_truth ? s.truth.yaw_rad : kNaN);
  }
  for (const std::string& comment : log.header.comments) {
    if (comment == "truth_clock: shared") d.truth_clock_shared = true;
    if (comment == "truth_clock: same_rate") d.truth_clock_same_rate = true;
    if (comment == "truth_frame: robot") d.truth_frame_is_robot = true;
  }
  // Motion capture reports a wrapped heading; unwrapped it interpolates and plots cleanly.
  double previous = kNaN;
  for (double& yaw : d.truth_yaw_rad) {
    if (!std::isfinite(yaw)) continue;
    if (std::isfinite(previous)) yaw = unwrap_near(yaw, previous);
    previous = yaw;
  }
  return d;
}

RunData load_run(const std::string& path) { return to_run_data(read_run_log(path)); }

}  // namespace swivel::model_gap
