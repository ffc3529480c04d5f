// SPDX-License-Identifier: Apache-2.0
#include "swivel/sim/open_loop.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <utility>

#include "swivel/differential/differential_kinematics.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"

namespace swivel::sim {
namespace {

// The pivot of the calibration motion: the locked module's contact point (robot frame).
void pivot(const SwpcModuleParams& m, double phi_rad, double& cx, double& cy) noexcept {
  cx = m.x_m - m.caster_offset_m * std::cos(phi_rad);
  cy = m.y_m - m.caster_offset_m * std::sin(phi_rad);
}

Twist2 rotation_about(double cx, double cy, double w) noexcept {
  return Twist2{w * cy, -w * cx, w};
}

}  // namespace

OpenLoopController::OpenLoopController(const RobotModel& nominal)
    : OpenLoopController(nominal, nominal.limits) {}

OpenLoopController::OpenLoopController(RobotModel nominal, const MotionLimits& limits)
    : nominal_(std::move(nominal)),
      max_steer_rate_radps_(limits.steering_rate_radps.value_or(0.0)) {
  if (nominal_.drivetrain == DrivetrainKind::kSwpc) {
    if (nominal_.modules.size() < 2 || nominal_.modules.size() > kMaxModules) {
      throw std::invalid_argument("nominal model '" + nominal_.name + "': expected 2.." +
                                  std::to_string(kMaxModules) + " swpc modules");
    }
    for (const SwpcModuleParams& m : nominal_.modules) {
      if (!(m.caster_offset_m > 0.0) || !(m.wheel_radius_m > 0.0)) {
        throw std::invalid_argument("nominal model '" + nominal_.name +
                                    "': caster offsets and wheel radii must be positive");
      }
    }
  } else {
    const DifferentialParams& d = nominal_.differential;
    if (!(d.wheel_radius_left_m > 0.0) || !(d.wheel_radius_right_m > 0.0) ||
        !(d.track_width_m > 0.0)) {
      throw std::invalid_argument("nominal model '" + nominal_.name +
                                  "': wheel radii and track width must be positive");
    }
  }
}

void OpenLoopController::velocity(const Twist2& twist, const HardwareState& measured,
                                  ActuatorCommand& out) const noexcept {
  out = ActuatorCommand{};
  if (nominal_.drivetrain == DrivetrainKind::kDifferential) {
    out.module_count = 2;
    const differential::WheelRates rates =
        differential::inverse(nominal_.differential, twist.vx_mps, twist.wz_radps);
    out.wheel_rate_radps[0] = rates.left_radps;
    out.wheel_rate_radps[1] = rates.right_radps;
    return;
  }
  out.module_count = static_cast<std::uint32_t>(nominal_.modules.size());
  for (std::size_t i = 0; i < nominal_.modules.size(); ++i) {
    const SwpcModuleParams& m = nominal_.modules[i];
    const double phi = measured.steer_angle_rad[i] + m.steering_offset_rad;
    const swpc::ModuleRates rates = swpc::inverse_module(m, phi, twist);
    out.wheel_rate_radps[i] = rates.wheel_rate_radps;
    out.steer_rate_radps[i] =
        max_steer_rate_radps_ > 0.0
            ? std::clamp(rates.steer_rate_radps, -max_steer_rate_radps_, max_steer_rate_radps_)
            : rates.steer_rate_radps;
  }
}

bool OpenLoopController::calibration(const CalibrationMotion& motion, ActuatorCommand& out,
                                     Twist2& commanded) const noexcept {
  out = ActuatorCommand{};
  commanded = Twist2{};
  const std::size_t n = nominal_.modules.size();
  if (nominal_.drivetrain != DrivetrainKind::kSwpc || motion.locked_module >= n ||
      !std::isfinite(motion.locked_steer_meas_rad) || !std::isfinite(motion.yaw_rate_radps)) {
    return false;
  }
  out.module_count = static_cast<std::uint32_t>(n);
  const SwpcModuleParams& lm = nominal_.modules[motion.locked_module];
  double cx = 0.0;
  double cy = 0.0;
  pivot(lm, motion.locked_steer_meas_rad + lm.steering_offset_rad, cx, cy);
  const Twist2 twist = rotation_about(cx, cy, motion.yaw_rate_radps);
  bool ok = true;
  for (std::size_t i = 0; i < n; ++i) {
    if (i == motion.locked_module) {
      out.mode[i] = ModuleDriveMode::kLocked;
      continue;
    }
    out.mode[i] = ModuleDriveMode::kFreeSteer;
    double phi = 0.0;
    if (!swpc::self_aligned_steer_angle(nominal_.modules[i], twist, phi)) {
      ok = false;
      continue;
    }
    out.wheel_rate_radps[i] =
        swpc::inverse_module(nominal_.modules[i], phi, twist).wheel_rate_radps;
  }
  if (!ok) {
    for (std::size_t i = 0; i < n; ++i) out.wheel_rate_radps[i] = 0.0;
    return false;
  }
  commanded = twist;
  return true;
}

std::array<double, kMaxModules> aligned_steer_angles(const PlantParams& plant,
                                                     const Twist2& twist) noexcept {
  std::array<double, kMaxModules> phi{};
  if (plant.drivetrain != DrivetrainKind::kSwpc) return phi;
  for (std::size_t i = 0; i < plant.module_count; ++i) {
    double angle = 0.0;
    if (swpc::self_aligned_steer_angle(plant.modules[i], twist, angle)) phi[i] = angle;
  }
  return phi;
}

std::array<double, kMaxModules> calibration_steer_angles(const PlantParams& plant,
                                                         const CalibrationMotion& motion) noexcept {
  std::array<double, kMaxModules> phi{};
  if (plant.drivetrain != DrivetrainKind::kSwpc || motion.locked_module >= plant.module_count) {
    return phi;
  }
  const SwpcModuleParams& lm = plant.modules[motion.locked_module];
  const double locked_phi = motion.locked_steer_meas_rad + lm.steering_offset_rad;
  double cx = 0.0;
  double cy = 0.0;
  pivot(lm, locked_phi, cx, cy);
  const Twist2 twist = rotation_about(cx, cy, motion.yaw_rate_radps);
  phi = aligned_steer_angles(plant, twist);
  phi[motion.locked_module] = locked_phi;
  return phi;
}

RunLogSample make_run_log_sample(const HardwareState& reading, const Twist2& commanded) noexcept {
  RunLogSample s;
  s.t_s = reading.stamp_s;
  s.cmd = commanded;
  s.wheel_rad = reading.wheel_angle_rad;
  s.steer_rad = reading.steer_angle_rad;
  s.gyro_wz_radps = reading.gyro_wz_radps;
  s.has_truth = reading.motion_capture.valid;
  s.truth = reading.motion_capture.pose;
  return s;
}

}  // namespace swivel::sim
