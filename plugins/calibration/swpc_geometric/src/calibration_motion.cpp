// SPDX-License-Identifier: Apache-2.0
#include "swivel/calibration/calibration_motion.hpp"

#include <cmath>

#include "swivel/swpc/swpc_kinematics.hpp"

namespace swivel::calibration {

bool generate_calibration_motion(std::span<const SwpcModuleParams> truth,
                                 const CalibrationMotionOptions& options, std::mt19937_64& rng,
                                 CalibrationInput& out, std::string& error) {
  const std::size_t n = truth.size();
  if (n < 2 || options.locked_angles_meas_rad.empty() || !(options.yaw_rate_radps > 0.0) ||
      !(options.sample_rate_hz > 0.0) || !(options.rotation_rad != 0.0)) {
    error =
        "calibration motion: need >= 2 modules, locked angles, and positive rate and "
        "rotation";
    return false;
  }
  const double w = std::copysign(options.yaw_rate_radps, options.rotation_rad);
  const double duration_s = std::abs(options.rotation_rad) / options.yaw_rate_radps;
  const auto samples =
      static_cast<std::size_t>(std::floor(duration_s * options.sample_rate_hz)) + 1;
  const double dt = 1.0 / options.sample_rate_hz;
  std::normal_distribution<double> unit(0.0, 1.0);

  out.module_count = n;
  out.runs.clear();
  out.runs.reserve(n * options.locked_angles_meas_rad.size());
  for (std::size_t lm = 0; lm < n; ++lm) {
    for (const double locked_meas : options.locked_angles_meas_rad) {
      const SwpcModuleParams& locked = truth[lm];
      const double phi = locked_meas + locked.steering_offset_rad;
      // Pivot: the locked wheel's contact point c = p - d u, robot frame.
      const double cx = locked.x_m - locked.caster_offset_m * std::cos(phi);
      const double cy = locked.y_m - locked.caster_offset_m * std::sin(phi);
      // Rotation about c: every point q moves at w x (q - c), so the body twist is:
      const Twist2 twist{w * cy, -w * cx, w};

      LockedRun run;
      run.locked_module = lm;
      run.locked_steer_meas_rad = locked_meas;
      RunSeries& d = run.data;
      d.t_s.resize(samples);
      d.x_m.resize(samples);
      d.y_m.resize(samples);
      d.yaw_rad.resize(samples);
      d.wheel_angle_rad.assign(n, std::vector<double>(samples, 0.0));
      d.steer_angle_rad.assign(n, std::vector<double>(samples, 0.0));

      for (std::size_t m = 0; m < n; ++m) {
        if (m == lm) {
          std::fill(d.steer_angle_rad[m].begin(), d.steer_angle_rad[m].end(), locked_meas);
          continue;
        }
        double phi_free = 0.0;
        if (!swpc::self_aligned_steer_angle(truth[m], twist, phi_free)) {
          error = "calibration motion: module " + std::to_string(m + 1) +
                  " cannot self-align about module " + std::to_string(lm + 1) + "'s wheel";
          return false;
        }
        const double rate = swpc::inverse_module(truth[m], phi_free, twist).wheel_rate_radps;
        std::fill(d.steer_angle_rad[m].begin(), d.steer_angle_rad[m].end(),
                  phi_free - truth[m].steering_offset_rad);
        for (std::size_t k = 0; k < samples; ++k) {
          d.wheel_angle_rad[m][k] = rate * static_cast<double>(k) * dt;
        }
      }

      // World point under the pivot stays fixed: W = origin + R(yaw) c.
      const double yaw0 = options.start_pose.yaw_rad;
      const double wx = options.start_pose.x_m + std::cos(yaw0) * cx - std::sin(yaw0) * cy;
      const double wy = options.start_pose.y_m + std::sin(yaw0) * cx + std::cos(yaw0) * cy;
      const bool noisy = options.position_noise_m > 0.0 || options.yaw_noise_rad > 0.0;
      for (std::size_t k = 0; k < samples; ++k) {
        const double t = static_cast<double>(k) * dt;
        const double yaw = yaw0 + w * t;
        const double c = std::cos(yaw);
        const double s = std::sin(yaw);
        d.t_s[k] = t;
        d.x_m[k] = wx - (c * cx - s * cy);
        d.y_m[k] = wy - (s * cx + c * cy);
        double yaw_meas = yaw;
        if (noisy) {
          d.x_m[k] += options.position_noise_m * unit(rng);
          d.y_m[k] += options.position_noise_m * unit(rng);
          yaw_meas += options.yaw_noise_rad * unit(rng);
        }
        // Motion capture reports a wrapped heading; the calibration must unwrap it.
        d.yaw_rad[k] = wrap_pi(yaw_meas);
      }
      out.runs.push_back(std::move(run));
    }
  }
  return true;
}

}  // namespace swivel::calibration
