// SPDX-License-Identifier: Apache-2.0
// The second generator's robots: none of them is the docent or swpc4 of the project.

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/second/second_robot.hpp"

namespace swivel::second {
namespace {

Design swpc_base(const std::string& name) {
  Design d;
  d.name = name;
  d.drive = Drive::kSwpc;
  return d;
}

// Modules evenly on a circle of `radius`, the first at `first_deg`.
std::vector<CasterModule> ring(std::size_t n, double radius, double first_deg, double trail,
                               double wheel) {
  std::vector<CasterModule> m;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = (first_deg + 360.0 * static_cast<double>(i) / static_cast<double>(n)) *
                     3.14159265358979323846 / 180.0;
    m.push_back({radius * std::cos(a), radius * std::sin(a), trail, wheel});
  }
  return m;
}

}  // namespace

std::vector<std::string> design_names() {
  return {"trike3", "cart4", "hex6", "mini_diff", "wide_diff", "mid_diff"};
}

Design design(const std::string& name) {
  if (name == "trike3") {
    Design d = swpc_base(name);
    d.modules = ring(3, 0.26, 0.0, 0.030, 0.050);
    d.wheel_counts_per_rev = 2048;
    d.steering_counts_per_rev = 2048;
    d.gyro_noise_rad_s = 0.003;
    d.mocap_position_noise_m = 0.0005;
    d.mocap_yaw_noise_rad = 0.002;
    d.mocap_rate_hz = 120;
    d.linear_accel_limit_mps2 = 0.5;
    d.angular_accel_limit_radps2 = 1.5;
    d.steering_rate_limit_radps = 8.0;
    d.max_speed_mps = 0.3;
    d.max_yaw_rate_radps = 0.8;
    d.mass_kg = 18;
    d.yaw_inertia_kgm2 = 0.6;
    return d;
  }
  if (name == "cart4") {
    Design d = swpc_base(name);
    d.modules = {{0.30, 0.20, 0.040, 0.075},
                 {-0.30, 0.20, 0.040, 0.075},
                 {-0.30, -0.20, 0.040, 0.075},
                 {0.30, -0.20, 0.040, 0.075}};
    d.wheel_counts_per_rev = 8192;
    d.steering_counts_per_rev = 2000;
    d.gyro_noise_rad_s = 0.0015;
    d.mocap_position_noise_m = 0.0002;
    d.mocap_yaw_noise_rad = 0.0008;
    d.mocap_rate_hz = 240;
    d.linear_accel_limit_mps2 = 0.8;
    d.angular_accel_limit_radps2 = 2.5;
    d.steering_rate_limit_radps = 5.0;
    d.max_speed_mps = 0.45;
    d.max_yaw_rate_radps = 1.0;
    d.mass_kg = 40;
    d.yaw_inertia_kgm2 = 1.73;
    return d;
  }
  if (name == "hex6") {
    Design d = swpc_base(name);
    d.modules = ring(6, 0.40, 30.0, 0.025, 0.040);
    d.wheel_counts_per_rev = 16384;
    d.steering_counts_per_rev = 16384;
    d.gyro_noise_rad_s = 0.002;
    d.mocap_position_noise_m = 0.0003;
    d.mocap_yaw_noise_rad = 0.001;
    d.mocap_rate_hz = 100;
    d.linear_accel_limit_mps2 = 0.4;
    d.angular_accel_limit_radps2 = 1.2;
    d.steering_rate_limit_radps = 6.0;
    d.max_speed_mps = 0.3;
    d.max_yaw_rate_radps = 0.6;
    d.mass_kg = 60;
    d.yaw_inertia_kgm2 = 4.8;
    return d;
  }
  Design d;
  d.name = name;
  d.drive = Drive::kDifferential;
  if (name == "mini_diff") {
    d.wheel_radius_left_m = d.wheel_radius_right_m = 0.033;
    d.track_width_m = 0.16;
    d.wheel_counts_per_rev = 1440;
    d.gyro_noise_rad_s = 0.004;
    d.mocap_position_noise_m = 0.0005;
    d.mocap_yaw_noise_rad = 0.002;
    d.mocap_rate_hz = 60;
    d.linear_accel_limit_mps2 = 1.0;
    d.angular_accel_limit_radps2 = 4.0;
    d.max_speed_mps = 0.25;
    d.max_yaw_rate_radps = 1.5;
    d.mass_kg = 3;
    d.yaw_inertia_kgm2 = 0.012;
    return d;
  }
  if (name == "wide_diff") {
    d.wheel_radius_left_m = d.wheel_radius_right_m = 0.10;
    d.track_width_m = 0.56;
    d.wheel_counts_per_rev = 3600;
    d.gyro_noise_rad_s = 0.0015;
    d.mocap_position_noise_m = 0.0003;
    d.mocap_yaw_noise_rad = 0.001;
    d.mocap_rate_hz = 100;
    d.linear_accel_limit_mps2 = 0.5;
    d.angular_accel_limit_radps2 = 1.2;
    d.max_speed_mps = 0.5;
    d.max_yaw_rate_radps = 0.8;
    d.mass_kg = 50;
    d.yaw_inertia_kgm2 = 2.0;
    return d;
  }
  if (name == "mid_diff") {
    d.wheel_radius_left_m = d.wheel_radius_right_m = 0.06;
    d.track_width_m = 0.30;
    d.wheel_counts_per_rev = 2000;
    d.gyro_noise_rad_s = 0.0025;
    d.mocap_position_noise_m = 0.0004;
    d.mocap_yaw_noise_rad = 0.0015;
    d.mocap_rate_hz = 150;
    d.linear_accel_limit_mps2 = 0.7;
    d.angular_accel_limit_radps2 = 2.0;
    d.max_speed_mps = 0.4;
    d.max_yaw_rate_radps = 1.2;
    d.mass_kg = 12;
    d.yaw_inertia_kgm2 = 0.25;
    return d;
  }
  std::string known;
  for (const auto& n : design_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown robot '" + name + "' (robots: " + known + ")");
}

const char* script_name(Script s) {
  switch (s) {
    case Script::kWaypoints: return "waypoints";
    case Script::kCircles: return "circles";
    case Script::kSpotTurns: return "spot_turns";
    case Script::kMixed: return "mixed";
  }
  return "?";
}

}  // namespace swivel::second
