#include "calibration_plugin.hpp"

#include <algorithm>
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

double wrap_angle(double angle_rad) noexcept {
  return std::remainder(angle_rad, 2.0 * std::numbers::pi);
}

}  // namespace

void SwpcGeometricCalibration::configure(const PluginContext& ctx) {
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  if (ctx.robot == nullptr || ctx.robot->drivetrain != DrivetrainKind::kSwpc) {
    params.fail("", "swpc_geometric calibrates swpc robots only; the robot model has none");
  }
  nominal_ = *ctx.robot;
  n_ = static_cast<std::uint32_t>(nominal_.modules.size());
  if (n_ < 2 || n_ > kMaxModules) {
    params.fail("", "swpc_geometric needs 2 to " + std::to_string(kMaxModules) +
                        " modules, the robot model has " + std::to_string(n_));
  }

  locked_angles_rad_ = {45.0 * kDegToRad, 165.0 * kDegToRad};
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
      locked_angles_rad_[k] = deg * kDegToRad;
    }
    if (std::abs(wrap_angle(locked_angles_rad_[1] - locked_angles_rad_[0])) < 20.0 * kDegToRad) {
      params.fail("locked_angles_deg", "the two locked angles must differ by at least 20 degrees");
    }
  }
  const double yaw_rate = params.number_or("yaw_rate_radps", 0.3, 0.01, 3.0);
  yaw_sign_ = params.choice_or("direction", "ccw", {"ccw", "cw"}) == "ccw" ? 1.0 : -1.0;
  rotation_rad_ = params.number_or("rotation_deg", 300.0, 30.0, 340.0) * kDegToRad;
  settle_s_ = params.number_or("settle_s", 1.0, 0.0, 60.0);
  stop_s_ = params.number_or("stop_s", 0.5, 0.0, 60.0);
  align_tolerance_rad_ = params.number_or("align_tolerance_deg", 0.5, 0.01, 10.0) * kDegToRad;
  align_hold_s_ = params.number_or("align_hold_s", 0.1, 0.0, 10.0);
  align_timeout_s_ = params.number_or("align_timeout_s", 10.0, 0.1, 600.0);
  steer_gain_per_s_ = params.number_or("steer_gain_per_s", 4.0, 0.1, 100.0);
  max_steer_rate_radps_ = params.number_or("max_steer_rate_radps", 2.0, 0.01, 100.0);
  const double max_wheel_rate = params.number_or("max_wheel_rate_radps", 30.0, 0.1, 1e4);
  run_timeout_s_ =
      params.number_or("run_timeout_s", 3.0 * rotation_rad_ / yaw_rate + 5.0, 1.0, 3600.0);
  mocap_timeout_s_ = params.number_or("motion_capture_timeout_s", 0.5, 0.01, 60.0);
  drive_mode_ = params.choice_or("wheel_drive", "torque", {"torque", "velocity"}) == "torque"
                    ? ModuleDriveMode::kTorque
                    : ModuleDriveMode::kFreeSteer;
  params.finish();

  // Plans: where the casters self-align about each pivot, and the wheel rates that agree
  // with a rotation at yaw_rate (nominal model; measured steering = true - offset).
  plans_.assign(static_cast<std::size_t>(n_) * kRunsPerModule, RunPlan{});
  for (std::uint32_t m = 0; m < n_; ++m) {
    const SwpcModuleParams& lock = nominal_.modules[m];
    for (std::uint32_t k = 0; k < kRunsPerModule; ++k) {
      RunPlan& plan = plans_[m * kRunsPerModule + k];
      plan.locked = m;
      plan.start_steer_meas_rad[m] = locked_angles_rad_[k];
      const double phi = locked_angles_rad_[k] + lock.steering_offset_rad;
      const double px = lock.x_m - lock.caster_offset_m * std::cos(phi);
      const double py = lock.y_m - lock.caster_offset_m * std::sin(phi);
      for (std::uint32_t i = 0; i < n_; ++i) {
        if (i == m) continue;
        const SwpcModuleParams& p = nominal_.modules[i];
        const double qx = p.x_m - px;
        const double qy = p.y_m - py;
        const double q = std::hypot(qx, qy);
        if (!(q > 1.5 * p.caster_offset_m)) {
          params.fail("locked_angles_deg",
                      "module " + std::to_string(i + 1) + " is too close to module " +
                          std::to_string(m + 1) + "'s pivot to self-align about it");
        }
        // Self-aligned: heading u with u . q = d, turned towards the direction of travel.
        const double heading =
            std::atan2(qy, qx) + yaw_sign_ * std::acos(p.caster_offset_m / q);
        plan.start_steer_meas_rad[i] = wrap_angle(heading - p.steering_offset_rad);
        const double lever = std::sqrt(q * q - p.caster_offset_m * p.caster_offset_m);
        plan.wheel_rate_radps[i] = lever * yaw_rate / p.wheel_radius_m;
        if (plan.wheel_rate_radps[i] > max_wheel_rate) {
          params.fail("yaw_rate_radps", "module " + std::to_string(i + 1) + " would need " +
                                            std::to_string(plan.wheel_rate_radps[i]) +
                                            " rad/s, above max_wheel_rate_radps");
        }
      }
    }
  }

  // At most one sample per cycle; the motion-capture rate (with margin for jitter) when
  // it is slower.
  const double rate_hz = std::min(1.5 * nominal_.sensors.motion_capture.rate_hz, 1.0 / ctx.period_s);
  capacity_ = static_cast<std::size_t>(std::ceil(run_timeout_s_ * rate_hz)) + 16;
  runs_.assign(plans_.size(), RunBuffer{});
  for (RunBuffer& run : runs_) {
    for (auto* series : {&run.t_s, &run.x_m, &run.y_m, &run.yaw_rad}) series->assign(capacity_, 0.0);
    run.wheel_rad.assign(capacity_ * n_, 0.0);
    run.steer_rad.assign(capacity_ * n_, 0.0);
  }
  run_ = 0;
  phase_ = CalibrationPhase::kIdle;
  finished_.store(false);
  failed_.store(false);
  last_error_.store("");
  publish_progress(0.0);
}

CalibrationProgress SwpcGeometricCalibration::progress() const noexcept {
  CalibrationProgress p;
  const std::uint32_t run = progress_run_.load(std::memory_order_relaxed);
  p.module = run / kRunsPerModule;
  p.run = run % kRunsPerModule;
  p.module_count = n_;
  p.runs_per_module = kRunsPerModule;
  p.fraction = progress_fraction_.load(std::memory_order_relaxed);
  p.phase = progress_phase_.load(std::memory_order_relaxed);
  return p;
}

void SwpcGeometricCalibration::publish_progress(double run_fraction) noexcept {
  const double total = static_cast<double>(plans_.empty() ? 1 : plans_.size());
  const std::size_t run = std::min(run_, plans_.empty() ? 0 : plans_.size() - 1);
  const double done = phase_ == CalibrationPhase::kDone
                          ? 1.0
                          : (static_cast<double>(run_) + std::clamp(run_fraction, 0.0, 1.0)) / total;
  progress_run_.store(static_cast<std::uint32_t>(run), std::memory_order_relaxed);
  progress_phase_.store(phase_, std::memory_order_relaxed);
  progress_fraction_.store(std::clamp(done, 0.0, 1.0), std::memory_order_relaxed);
}

void SwpcGeometricCalibration::enter(CalibrationPhase phase, double now_s) noexcept {
  phase_ = phase;
  phase_start_s_ = now_s;
  aligned_since_s_ = -1.0;
}

Status SwpcGeometricCalibration::fail(const char* reason) noexcept {
  last_error_.store(reason, std::memory_order_release);
  phase_ = CalibrationPhase::kFailed;
  failed_.store(true, std::memory_order_release);
  publish_progress(0.0);
  return Status::kError;
}

void SwpcGeometricCalibration::drive(const RunPlan& plan, bool wheels_on,
                                     ActuatorCommand& out) const noexcept {
  for (std::uint32_t i = 0; i < n_; ++i) {
    out.steer_rate_radps[i] = 0.0;
    if (i == plan.locked) {
      out.mode[i] = ModuleDriveMode::kLocked;
      out.wheel_rate_radps[i] = 0.0;
    } else {
      out.mode[i] = drive_mode_;
      out.wheel_rate_radps[i] = wheels_on ? plan.wheel_rate_radps[i] : 0.0;
    }
  }
}

Status SwpcGeometricCalibration::record(const HardwareState& readings) noexcept {
  const MotionCaptureSample& mc = readings.motion_capture;
  if (!mc.valid) {
    if (readings.stamp_s - last_sample_s_ > mocap_timeout_s_) {
      return fail("no motion capture within motion_capture_timeout_s while recording");
    }
    return Status::kOk;
  }
  RunBuffer& run = runs_[run_];
  if (run.count >= capacity_) return fail("more motion-capture samples than configured for");
  if (run.count == 0) {
    previous_yaw_rad_ = mc.pose.yaw_rad;
    travel_rad_ = 0.0;
  } else {
    travel_rad_ += wrap_angle(mc.pose.yaw_rad - previous_yaw_rad_);
    previous_yaw_rad_ = mc.pose.yaw_rad;
  }
  const std::size_t k = run.count;
  // Encoders of the same cycle: one clock for both, as the run logs have it.
  run.t_s[k] = readings.stamp_s;
  run.x_m[k] = mc.pose.x_m;
  run.y_m[k] = mc.pose.y_m;
  run.yaw_rad[k] = k == 0 ? mc.pose.yaw_rad : run.yaw_rad[0] + travel_rad_;  // unwrapped
  for (std::uint32_t i = 0; i < n_; ++i) {
    run.wheel_rad[k * n_ + i] = readings.wheel_angle_rad[i];
    run.steer_rad[k * n_ + i] = readings.steer_angle_rad[i];
  }
  run.locked_steer_sum_rad += readings.steer_angle_rad[plans_[run_].locked];
  run.count = k + 1;
  last_sample_s_ = readings.stamp_s;
  return Status::kOk;
}

Status SwpcGeometricCalibration::step(const HardwareState& readings, ActuatorCommand& out) noexcept {
  out = ActuatorCommand{};
  out.module_count = n_;
  if (phase_ == CalibrationPhase::kFailed) return Status::kError;
  if (phase_ == CalibrationPhase::kDone) return Status::kOk;
  if (readings.module_count != n_) return fail("readings have a different module count");
  const double now_s = readings.stamp_s;
  if (phase_ == CalibrationPhase::kIdle) enter(CalibrationPhase::kAligning, now_s);
  const RunPlan& plan = plans_[run_];
  const double in_phase_s = now_s - phase_start_s_;

  switch (phase_) {
    case CalibrationPhase::kAligning: {
      bool aligned = true;
      for (std::uint32_t i = 0; i < n_; ++i) {
        const double error = wrap_angle(plan.start_steer_meas_rad[i] - readings.steer_angle_rad[i]);
        aligned = aligned && std::abs(error) <= align_tolerance_rad_;
        out.mode[i] = ModuleDriveMode::kVelocity;
        out.wheel_rate_radps[i] = 0.0;
        out.steer_rate_radps[i] = std::clamp(steer_gain_per_s_ * error, -max_steer_rate_radps_,
                                             max_steer_rate_radps_);
      }
      if (!aligned) {
        aligned_since_s_ = -1.0;
      } else if (aligned_since_s_ < 0.0) {
        aligned_since_s_ = now_s;
      }
      if (aligned && now_s - aligned_since_s_ >= align_hold_s_) {
        enter(CalibrationPhase::kSettling, now_s);
        drive(plan, true, out);
      } else if (in_phase_s > align_timeout_s_) {
        return fail("steering did not reach the start angles within align_timeout_s");
      }
      publish_progress(0.0);
      return Status::kOk;
    }
    case CalibrationPhase::kSettling:
      drive(plan, true, out);
      if (in_phase_s >= settle_s_) {
        enter(CalibrationPhase::kRecording, now_s);
        runs_[run_].count = 0;
        runs_[run_].locked_steer_sum_rad = 0.0;
        last_sample_s_ = now_s;
        travel_rad_ = 0.0;
      }
      publish_progress(0.05);
      return Status::kOk;
    case CalibrationPhase::kRecording: {
      drive(plan, true, out);
      if (record(readings) != Status::kOk) {
        out = ActuatorCommand{};
        out.module_count = n_;
        return Status::kError;
      }
      const double turned = travel_rad_ * yaw_sign_;
      if (turned >= rotation_rad_) {
        enter(CalibrationPhase::kStopping, now_s);
        drive(plan, false, out);
      } else if (in_phase_s > run_timeout_s_) {
        out = ActuatorCommand{};
        out.module_count = n_;
        return fail("the robot did not turn rotation_deg within run_timeout_s");
      }
      publish_progress(0.05 + 0.9 * std::max(0.0, turned) / rotation_rad_);
      return Status::kOk;
    }
    case CalibrationPhase::kStopping:
      drive(plan, false, out);
      if (in_phase_s >= stop_s_) {
        ++run_;
        if (run_ >= plans_.size()) {
          run_ = plans_.size();
          enter(CalibrationPhase::kDone, now_s);
          out = ActuatorCommand{};
          out.module_count = n_;
          publish_progress(1.0);
          finished_.store(true, std::memory_order_release);
          return Status::kOk;
        }
        enter(CalibrationPhase::kAligning, now_s);
      }
      publish_progress(phase_ == CalibrationPhase::kStopping ? 0.95 : 0.0);
      return Status::kOk;
    default:
      return fail("unknown calibration phase");
  }
}

CalibrationReport SwpcGeometricCalibration::analyse() {
  CalibrationReport report;
  if (!finished()) {
    report.reason = failed() ? std::string("the procedure failed: ") + last_error()
                             : "the procedure did not finish";
    return report;
  }
  calibration::CalibrationInput input;
  input.module_count = n_;
  for (std::size_t j = 0; j < runs_.size(); ++j) {
    const RunBuffer& buffer = runs_[j];
    const std::size_t count = buffer.count;
    calibration::LockedRun run;
    run.locked_module = plans_[j].locked;
    run.locked_steer_meas_rad =
        count > 0 ? buffer.locked_steer_sum_rad / static_cast<double>(count) : 0.0;
    auto head = [count](const std::vector<double>& v) {
      return std::vector<double>(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(count));
    };
    run.data.t_s = head(buffer.t_s);
    run.data.x_m = head(buffer.x_m);
    run.data.y_m = head(buffer.y_m);
    run.data.yaw_rad = head(buffer.yaw_rad);
    run.data.wheel_angle_rad.assign(n_, std::vector<double>(count));
    run.data.steer_angle_rad.assign(n_, std::vector<double>(count));
    for (std::size_t k = 0; k < count; ++k) {
      for (std::uint32_t i = 0; i < n_; ++i) {
        run.data.wheel_angle_rad[i][k] = buffer.wheel_rad[k * n_ + i];
        run.data.steer_angle_rad[i][k] = buffer.steer_rad[k * n_ + i];
      }
    }
    input.runs.push_back(std::move(run));
  }
  const calibration::CalibrationResult result =
      calibration::calibrate(input, calibration::calibration_options_for(nominal_));
  report.verdict = result.verdict.text();
  report.ok = result.ok();
  if (!report.ok) {
    report.reason = result.reason().empty() ? "the calibration refused the data" : result.reason();
    return report;
  }
  report.model = calibration::calibrated_model(nominal_, result);
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
