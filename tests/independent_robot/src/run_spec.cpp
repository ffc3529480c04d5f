// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/run_spec.hpp"

#include <cmath>
#include <stdexcept>

#include "assignment.hpp"
#include "effect_checks.hpp"
#include "swivel/independent/tour.hpp"

namespace swivel::independent {
namespace {

void require(bool ok, const std::string& field, double value, const std::string& expected) {
  if (!ok) {
    throw std::invalid_argument(field + "=" + format_number(value) + ": expected " + expected);
  }
}

void check_noise(const NoiseSpec& n) {
  const auto non_negative = [](const char* field, double v) {
    require(std::isfinite(v) && v >= 0.0, std::string("noise.") + field, v, ">= 0");
  };
  non_negative("slip_std", n.slip_std);
  non_negative("gyro_noise_rad_s", n.gyro_noise_rad_s);
  non_negative("mocap_position_noise_m", n.mocap_position_noise_m);
  non_negative("mocap_yaw_noise_rad", n.mocap_yaw_noise_rad);
  non_negative("row_jitter_s", n.row_jitter_s);
  non_negative("row_jitter_clip_s", n.row_jitter_clip_s);
  require(n.slip_correlation_s > 0.0 && std::isfinite(n.slip_correlation_s),
          "noise.slip_correlation_s", n.slip_correlation_s, "> 0");
  require(n.row_rate_hz >= 1.0 && n.row_rate_hz <= 1000.0, "noise.row_rate_hz", n.row_rate_hz,
          "within [1, 1000]");
  require(n.mocap_rate_hz >= 1.0 && n.mocap_rate_hz <= 1000.0, "noise.mocap_rate_hz",
          n.mocap_rate_hz, "within [1, 1000]");
  require(std::abs(n.mocap_clock_ppm) <= 1000.0, "noise.mocap_clock_ppm", n.mocap_clock_ppm,
          "within [-1000, 1000]");
  require(n.mocap_dropout >= 0.0 && n.mocap_dropout < 1.0, "noise.mocap_dropout", n.mocap_dropout,
          "within [0, 1)");
  // Clipped jitter below half a period keeps the row times strictly increasing.
  require(n.row_jitter_clip_s < 0.5 / n.row_rate_hz, "noise.row_jitter_clip_s", n.row_jitter_clip_s,
          "below half the row period");
}

}  // namespace

std::string robot_name(Robot robot) { return robot == Robot::kDocent ? "docent" : "swpc4"; }

std::size_t wheel_count(Robot robot) { return robot == Robot::kDocent ? 2U : 4U; }

NoiseSpec NoiseSpec::quiet() {
  NoiseSpec n;
  n.slip_std = 0.0;
  n.gyro_noise_rad_s = 0.0;
  n.mocap_position_noise_m = 0.0;
  n.mocap_yaw_noise_rad = 0.0;
  n.mocap_dropout = 0.0;
  n.row_jitter_s = 0.0;
  return n;
}

void validate(const RunSpec& spec) {
  require(std::isfinite(spec.duration_s) && spec.duration_s >= 2.0 && spec.duration_s <= 3600.0,
          "duration_s", spec.duration_s, "within [2, 3600]");
  if (spec.robot == Robot::kDocent && spec.steering != Steering::kPowered) {
    throw std::invalid_argument("steering: self_aligning applies to the swpc4 robot only");
  }
  check_true_effects(spec);
  check_outside_effects(spec);
  check_noise(spec.noise);
  if (!spec.tour.empty()) validate_tour(spec.robot, spec.tour);
  if (spec.start_pose) {
    const Pose& p = *spec.start_pose;
    if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.yaw_rad)) {
      throw std::invalid_argument("start_pose: expected finite numbers");
    }
  }
}

}  // namespace swivel::independent
