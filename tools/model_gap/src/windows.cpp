// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/windows.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace swivel::model_gap {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool has_mocap(const RunData& run, std::size_t k) { return std::isfinite(run.truth_x_m[k]); }

}  // namespace

std::vector<Window> make_windows(const RunData& run, double length_s, double first_s,
                                 double last_s) {
  std::vector<Window> out;
  const std::size_t n = run.size();
  bool any_mocap = false;
  for (std::size_t k = 0; k < n && !any_mocap; ++k) any_mocap = has_mocap(run, k);
  const auto usable = [&](std::size_t k) { return !any_mocap || has_mocap(run, k); };
  std::size_t a = 0;
  while (a < n && (run.t_s[a] < first_s || !usable(a))) ++a;
  while (a < n) {
    std::size_t b = a + 1;
    while (b < n && (run.t_s[b] - run.t_s[a] < length_s || !usable(b))) ++b;
    if (b >= n || run.t_s[b] > last_s) break;
    if (run.t_s[b] - run.t_s[a] <= 2.0 * length_s) {
      out.push_back({a, b});
      a = b;
    } else {
      // A gap in the motion capture: start again at the next row that has it.
      a = b;
    }
  }
  return out;
}

WindowMotion window_motion(const RunData& run, const std::vector<Window>& windows) {
  WindowMotion m;
  const std::size_t modules = run.module_count;
  const std::size_t w = windows.size();
  m.start_s.resize(w);
  m.duration_s.resize(w);
  m.wheel_travel_rad.resize(w);
  m.steer_travel_rad.assign(w, 0.0);
  m.accel_mps2.resize(w);
  m.angular_accel_radps2.resize(w);
  m.start_yaw_rad.resize(w);
  m.wheel_sin_change.assign(modules, std::vector<double>(w));
  m.wheel_cos_change.assign(modules, std::vector<double>(w));
  for (std::size_t j = 0; j < w; ++j) {
    const Window& win = windows[j];
    m.start_s[j] = run.t_s[win.a];
    m.duration_s[j] = run.t_s[win.b] - run.t_s[win.a];
    double travel = 0.0;
    for (std::size_t i = 0; i < modules; ++i) {
      const double pa = run.wheel_rad[i][win.a];
      const double pb = run.wheel_rad[i][win.b];
      travel += std::abs(pb - pa);
      m.wheel_sin_change[i][j] = std::sin(pb) - std::sin(pa);
      m.wheel_cos_change[i][j] = std::cos(pb) - std::cos(pa);
      if (!run.steer_rad.empty()) {
        double steer = 0.0;
        for (std::size_t k = win.a + 1; k <= win.b; ++k) {
          steer += std::abs(run.steer_rad[i][k] - run.steer_rad[i][k - 1]);
        }
        m.steer_travel_rad[j] += steer / static_cast<double>(modules);
      }
    }
    m.wheel_travel_rad[j] = travel / static_cast<double>(modules);
    double accel = 0.0;
    double angular = 0.0;
    if (run.has_commands) {
      for (std::size_t k = win.a + 1; k <= win.b; ++k) {
        accel += std::hypot(run.cmd_vx_mps[k] - run.cmd_vx_mps[k - 1],
                            run.cmd_vy_mps[k] - run.cmd_vy_mps[k - 1]);
        angular += std::abs(run.cmd_wz_radps[k] - run.cmd_wz_radps[k - 1]);
      }
    } else {
      // Without commands: how much the wheels' rates changed (rad/s, a regressor whose scale
      // does not matter), from rates over +-2 rows to keep encoder quantization out.
      const auto rate = [&run](std::size_t i, std::size_t k) {
        const std::size_t lo = k >= 2 ? k - 2 : 0;
        const std::size_t hi = std::min(run.size() - 1, k + 2);
        const double dt = run.t_s[hi] - run.t_s[lo];
        return dt > 0.0 ? (run.wheel_rad[i][hi] - run.wheel_rad[i][lo]) / dt : 0.0;
      };
      for (std::size_t k = win.a + 1; k <= win.b; ++k) {
        for (std::size_t i = 0; i < modules; ++i)
          accel += std::abs(rate(i, k) - rate(i, k - 1)) / static_cast<double>(modules);
      }
    }
    const double d = std::max(m.duration_s[j], 1e-9);
    m.accel_mps2[j] = accel / d;
    m.angular_accel_radps2[j] = angular / d;
    m.start_yaw_rad[j] = run.truth_yaw_rad[win.a];
  }
  return m;
}

std::vector<std::vector<double>> slowest_roll_offsets(const RunData& run,
                                                      const std::vector<Window>& windows,
                                                      const RobotModel& model) {
  std::vector<std::vector<double>> out;
  if (model.drivetrain != DrivetrainKind::kSwpc || !run.has_commands) return out;
  for (const SwpcModuleParams& m : model.modules) {
    std::vector<double>& roll = out.emplace_back(windows.size(), kNaN);
    if (!(m.caster_offset_m > 0.0)) continue;
    for (std::size_t j = 0; j < windows.size(); ++j) {
      const Window& win = windows[j];
      double slowest = std::numeric_limits<double>::infinity();
      for (std::size_t k = win.a; k <= win.b; ++k) {
        const double w = run.cmd_wz_radps[k];
        slowest = std::min(
            slowest, std::hypot(run.cmd_vx_mps[k] - w * m.y_m, run.cmd_vy_mps[k] + w * m.x_m));
      }
      roll[j] = slowest * (run.t_s[win.b] - run.t_s[win.a]) / m.caster_offset_m;
    }
  }
  return out;
}

Pose2 anchor(const RunData& run, const std::vector<Pose2>& shape, std::size_t row,
             std::size_t half_width) {
  if (!has_mocap(run, row)) return Pose2{kNaN, kNaN, kNaN};
  const std::size_t lo = row >= half_width ? row - half_width : 0;
  const std::size_t hi = std::min(run.size() - 1, row + half_width);
  // The path's frame may be turned against the world's (a dead-reckoned heading drifts), so
  // the local offset is the heading difference and the mean positions: anchor =
  // mean(M) + R(heading offset) (S_row - mean(S)), which is exact for any frame turn.
  double mx = 0.0;
  double my = 0.0;
  double sx = 0.0;
  double sy = 0.0;
  double dyaw = 0.0;
  double count = 0.0;
  for (std::size_t k = lo; k <= hi; ++k) {
    if (!has_mocap(run, k) || !std::isfinite(shape[k].x_m)) continue;
    mx += run.truth_x_m[k];
    my += run.truth_y_m[k];
    sx += shape[k].x_m;
    sy += shape[k].y_m;
    dyaw += run.truth_yaw_rad[k] - shape[k].yaw_rad;
    count += 1.0;
  }
  if (count == 0.0) return Pose2{run.truth_x_m[row], run.truth_y_m[row], run.truth_yaw_rad[row]};
  mx /= count;
  my /= count;
  sx /= count;
  sy /= count;
  dyaw /= count;
  const double c = std::cos(dyaw);
  const double s = std::sin(dyaw);
  const double ex = shape[row].x_m - sx;
  const double ey = shape[row].y_m - sy;
  return Pose2{mx + c * ex - s * ey, my + s * ex + c * ey, shape[row].yaw_rad + dyaw};
}

}  // namespace swivel::model_gap
