// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/run_files.hpp"

#include <string>

#include "assignment.hpp"
#include "swivel/independent/nominal_robots.hpp"

namespace swivel::independent {
namespace {

void cell(std::string& line, double value) {
  line += ',';
  line += format_number(value);
}

// YAML numbers with a decimal point, so that a reader sees floats where the schema has them.
std::string yaml_number(double value) {
  std::string text = format_number(value);
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

}  // namespace

std::string run_log_csv(const RunSpec& spec, const RunRecord& record) {
  const bool swpc = spec.robot == Robot::kSwpc4;
  const std::size_t n = wheel_count(spec.robot);
  std::string out;
  out.reserve(record.rows.size() * (swpc ? 230 : 150) + 512);
  out += "# swivel-run 1\n";
  out += "# robot: " + robot_name(spec.robot) + "\n";
  out += swpc ? "# drivetrain: swpc\n# modules: 4\n" : "# drivetrain: differential\n";
  // Its gyro reports the mean rate since the previous row (simulation.cpp).
  out += "# gyro_wz: mean over the row\n";
  // Its motion capture is the simulated truth, stamped on the same clock as the encoders.
  out += "# truth_clock: shared\n";
  out += "# truth_frame: robot\n";
  out += "# source: swivel-independent-run (independent robot generator), seed " +
         std::to_string(spec.seed) + "\n";
  out += "t,cmd_vx,cmd_vy,cmd_wz";
  if (swpc) {
    for (std::size_t i = 1; i <= n; ++i) out += ",steer_" + std::to_string(i);
    for (std::size_t i = 1; i <= n; ++i) out += ",wheel_" + std::to_string(i);
  } else {
    out += ",wheel_l,wheel_r";
  }
  out += ",gyro_wz,truth_x,truth_y,truth_yaw\n";

  for (const RunRow& row : record.rows) {
    out += format_number(row.t_s);
    cell(out, row.cmd.vx_mps);
    cell(out, row.cmd.vy_mps);
    cell(out, row.cmd.wz_radps);
    if (swpc) {
      for (std::size_t i = 0; i < n; ++i) cell(out, row.steer_rad[i]);
    }
    for (std::size_t i = 0; i < n; ++i) cell(out, row.wheel_rad[i]);
    cell(out, row.gyro_wz_radps);
    if (row.has_truth) {
      cell(out, row.truth.x_m);
      cell(out, row.truth.y_m);
      cell(out, row.truth.yaw_rad);
    } else {
      out += ",,,";
    }
    out += '\n';
  }
  return out;
}

std::string nominal_model_yaml(const RunSpec& spec) {
  const bool swpc = spec.robot == Robot::kSwpc4;
  std::string y;
  if (swpc) {
    y +=
        "# swpc4: four single-wheel powered casters, docs/methods.md §1 design values (nominal).\n";
    y += "# Steering angles: measured = true - steering_offset_rad; contact trails the axis.\n";
    y += "name: swpc4\ndrivetrain: swpc\nswpc:\n  modules:\n";
    for (const SwpcModule& m : swpc4_nominal()) {
      y += "    - {x_m: " + yaml_number(m.x_m) + ", y_m: " + yaml_number(m.y_m) +
           ", steering_offset_rad: " + yaml_number(m.steering_offset_rad) +
           ", caster_offset_m: " + yaml_number(m.caster_offset_m) +
           ", wheel_radius_m: " + yaml_number(m.wheel_radius_m) + "}\n";
    }
  } else {
    const DifferentialGeometry g = docent_nominal();
    y += "# docent: differential drive (nominal).\n";
    y += "name: docent\ndrivetrain: differential\ndifferential:\n";
    y += "  wheel_radius_left_m: " + yaml_number(g.wheel_radius_left_m) + "\n";
    y += "  wheel_radius_right_m: " + yaml_number(g.wheel_radius_right_m) + "\n";
    y += "  track_width_m: " + yaml_number(g.track_width_m) + "\n";
  }
  y += "sensors:\n";
  y += "  wheel_encoder_counts_per_rev: " + std::to_string(kEncoderCountsPerRev) + "\n";
  if (swpc) {
    y += "  steering_encoder_counts_per_rev: " + std::to_string(kEncoderCountsPerRev) + "\n";
  }
  y += "  gyro: {scale: 1.0, bias_rad_s: 0.0, noise_rad_s: " + yaml_number(kGyroNoiseRadS) + "}\n";
  y += "  motion_capture: {position_noise_m: " + yaml_number(kMocapPositionNoiseM) +
       ", yaw_noise_rad: " + yaml_number(kMocapYawNoiseRad) +
       ", rate_hz: " + yaml_number(kMocapRateHz) + "}\n";
  const bool accel = spec.model_limits == ModelLimits::kAll;
  // Passive, self-aligning casters have no steering motor whose rate a limit could state:
  // they swing as fast as the motion turns them.
  const bool steering =
      swpc && spec.steering != Steering::kSelfAligning && spec.model_limits != ModelLimits::kNone;
  if (accel || steering) {
    y += "limits:\n";
    if (accel) {
      y += "  linear_acceleration_mps2: " + yaml_number(kLinearAccelLimitMps2) + "\n";
      y += "  angular_acceleration_radps2: " + yaml_number(kAngularAccelLimitRadps2) + "\n";
    }
    if (steering) {
      y += "  steering_rate_radps: " + yaml_number(kSteeringRateLimitRadps) + "\n";
    }
  }
  y += "effects: {}\n";
  return y;
}

}  // namespace swivel::independent
