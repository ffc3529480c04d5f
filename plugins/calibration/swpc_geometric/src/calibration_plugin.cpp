// SPDX-License-Identifier: Apache-2.0
#include "calibration_plugin.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "swivel/calibration/calibration_io.hpp"
#include "swivel/calibration/swpc_calibration.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/plugin/abi.hpp"

namespace swivel::plugins {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

// The parameter that sets a procedure option (the options are in SI units).
std::string parameter_of(const std::string& option) {
  if (option == "locked_angles_meas_rad") return "locked_angles_deg";
  if (option == "rotation_rad") return "rotation_deg";
  if (option == "align_tolerance_rad") return "align_tolerance_deg";
  return option;
}

}  // namespace

void SwpcGeometricCalibration::configure(const PluginContext& ctx) {
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  if (ctx.robot == nullptr || ctx.robot->drivetrain != DrivetrainKind::kSwpc) {
    params.fail("", "swpc_geometric calibrates swpc robots only; the robot model has none");
  }
  const std::size_t n = ctx.robot->modules.size();
  if (n < 2 || n > kMaxModules) {
    params.fail("", "swpc_geometric needs 2 to " + std::to_string(kMaxModules) +
                        " modules, the robot model has " + std::to_string(n));
  }

  calibration::ProcedureOptions o;
  if (params.has("locked_angles_deg")) {
    const YAML::Node angles = params.sequence("locked_angles_deg");
    if (!angles.IsSequence() || angles.size() != kRunsPerModule) {
      params.fail("locked_angles_deg", "expected a sequence of two angles in degrees");
    }
    for (std::size_t k = 0; k < kRunsPerModule; ++k) {
      double deg = 0.0;
      try {
        deg = angles[k].as<double>();
      } catch (const YAML::Exception&) {
        params.fail("locked_angles_deg", "expected numbers (degrees)");
      }
      if (!std::isfinite(deg) || std::abs(deg) > 360.0) {
        params.fail("locked_angles_deg", "expected angles within [-360, 360] degrees");
      }
      o.locked_angles_meas_rad[k] = deg * kDegToRad;
    }
    const double separation = std::remainder(
        o.locked_angles_meas_rad[1] - o.locked_angles_meas_rad[0], 2.0 * std::numbers::pi);
    if (std::abs(separation) < 20.0 * kDegToRad) {
      params.fail("locked_angles_deg", "the two locked angles must differ by at least 20 degrees");
    }
  }
  o.yaw_rate_radps = params.number_or("yaw_rate_radps", o.yaw_rate_radps, 0.01, 3.0);
  o.counter_clockwise = params.choice_or("direction", "ccw", {"ccw", "cw"}) == "ccw";
  o.rotation_rad = params.number_or("rotation_deg", 300.0, 30.0, 340.0) * kDegToRad;
  o.settle_s = params.number_or("settle_s", o.settle_s, 0.0, 60.0);
  o.stop_s = params.number_or("stop_s", o.stop_s, 0.0, 60.0);
  o.align_tolerance_rad = params.number_or("align_tolerance_deg", 0.5, 0.01, 10.0) * kDegToRad;
  o.align_hold_s = params.number_or("align_hold_s", o.align_hold_s, 0.0, 10.0);
  o.align_timeout_s = params.number_or("align_timeout_s", o.align_timeout_s, 0.1, 600.0);
  o.steer_gain_per_s = params.number_or("steer_gain_per_s", o.steer_gain_per_s, 0.1, 100.0);
  o.max_steer_rate_radps =
      params.number_or("max_steer_rate_radps", o.max_steer_rate_radps, 0.01, 100.0);
  o.max_wheel_rate_radps =
      params.number_or("max_wheel_rate_radps", o.max_wheel_rate_radps, 0.1, 1e4);
  o.run_timeout_s =
      params.number_or("run_timeout_s", 3.0 * o.rotation_rad / o.yaw_rate_radps + 5.0, 1.0, 3600.0);
  o.motion_capture_timeout_s =
      params.number_or("motion_capture_timeout_s", o.motion_capture_timeout_s, 0.01, 60.0);
  o.wheel_drive = params.choice_or("wheel_drive", "torque", {"torque", "velocity"}) == "torque"
                      ? calibration::WheelDrive::kTorque
                      : calibration::WheelDrive::kVelocity;
  params.finish();

  try {
    procedure_.emplace(*ctx.robot, o, ctx.period_s);
  } catch (const calibration::ProcedureConfigError& e) {
    params.fail(parameter_of(e.option()), e.what());
  }
  module_count_.store(static_cast<std::uint32_t>(n));
  finished_.store(false);
  failed_.store(false);
  last_error_.store("");
  publish();
}

void SwpcGeometricCalibration::publish() noexcept {
  const CalibrationProgress p = procedure_->progress();
  progress_run_.store(p.module * kRunsPerModule + p.run, std::memory_order_relaxed);
  progress_phase_.store(p.phase, std::memory_order_relaxed);
  progress_fraction_.store(p.fraction, std::memory_order_relaxed);
  if (procedure_->failed() && !failed_.load(std::memory_order_relaxed)) {
    last_error_.store(procedure_->last_error(), std::memory_order_release);
    failed_.store(true, std::memory_order_release);
  }
  if (procedure_->finished()) finished_.store(true, std::memory_order_release);
}

CalibrationProgress SwpcGeometricCalibration::progress() const noexcept {
  CalibrationProgress p;
  const std::uint32_t run = progress_run_.load(std::memory_order_relaxed);
  p.module = run / kRunsPerModule;
  p.run = run % kRunsPerModule;
  p.module_count = module_count_.load(std::memory_order_relaxed);
  p.runs_per_module = kRunsPerModule;
  p.fraction = progress_fraction_.load(std::memory_order_relaxed);
  p.phase = progress_phase_.load(std::memory_order_relaxed);
  return p;
}

Status SwpcGeometricCalibration::step(const HardwareState& readings,
                                      ActuatorCommand& out) noexcept {
  const Status status = procedure_->step(readings, out);
  publish();
  return status;
}

CalibrationReport SwpcGeometricCalibration::analyse() {
  CalibrationReport report;
  if (!finished()) {
    report.reason = failed() ? std::string("the procedure failed: ") + last_error()
                             : "the procedure did not finish";
    return report;
  }
  const calibration::CalibrationResult result = procedure_->analyse();
  report.verdict = result.verdict.text();
  report.ok = result.ok();
  if (!report.ok) {
    report.reason = result.reason().empty() ? "the calibration refused the data" : result.reason();
    return report;
  }
  report.model = calibration::calibrated_model(procedure_->nominal(), result);
  for (const calibration::ModuleCalibration& m : result.modules) {
    report.uncertainty.push_back({m.sigma.x_m, m.sigma.y_m, m.sigma.steering_offset_rad,
                                  m.sigma.caster_offset_m, m.sigma.wheel_radius_m});
  }
  return report;
}

}  // namespace swivel::plugins

#ifndef SWIVEL_SWPC_GEOMETRIC_NO_EXPORT
SWIVEL_EXPORT_PLUGIN(swivel::plugins::SwpcGeometricCalibration, swivel::Calibration,
                     "swpc_geometric")
#endif
