// SPDX-License-Identifier: Apache-2.0
#include "swivel/calibration/calibration_procedure.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "swivel/calibration/calibration_io.hpp"
#include "swivel/run_log.hpp"

namespace swivel::calibration {
namespace {

double wrap_angle(double angle_rad) noexcept {
  return std::remainder(angle_rad, 2.0 * std::numbers::pi);
}

bool positive(double v) { return std::isfinite(v) && v > 0.0; }
bool non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

void check_options(const ProcedureOptions& o) {
  const auto require = [](bool ok, const char* option, const char* what) {
    if (!ok) throw ProcedureConfigError(option, std::string(option) + ": " + what);
  };
  require(positive(o.yaw_rate_radps), "yaw_rate_radps", "must be positive");
  require(positive(o.rotation_rad), "rotation_rad", "must be positive");
  for (const double a : o.locked_angles_meas_rad) {
    require(std::isfinite(a), "locked_angles_meas_rad", "must be finite");
  }
  require(non_negative(o.settle_s) && non_negative(o.stop_s) && non_negative(o.align_hold_s),
          "settle_s", "settle_s, stop_s and align_hold_s must not be negative");
  require(positive(o.align_tolerance_rad), "align_tolerance_rad", "must be positive");
  require(positive(o.align_timeout_s), "align_timeout_s", "must be positive");
  require(positive(o.steer_gain_per_s), "steer_gain_per_s", "must be positive");
  require(positive(o.max_steer_rate_radps), "max_steer_rate_radps", "must be positive");
  require(positive(o.max_wheel_rate_radps), "max_wheel_rate_radps", "must be positive");
  require(std::isfinite(o.run_timeout_s), "run_timeout_s", "must be finite");
  require(positive(o.motion_capture_timeout_s), "motion_capture_timeout_s", "must be positive");
}

}  // namespace

CalibrationProcedure::CalibrationProcedure(RobotModel nominal, const ProcedureOptions& options,
                                           double period_s)
    : nominal_(std::move(nominal)), options_(options) {
  if (nominal_.drivetrain != DrivetrainKind::kSwpc) {
    throw ProcedureConfigError("", "the calibration procedure needs an swpc robot");
  }
  n_ = static_cast<std::uint32_t>(nominal_.modules.size());
  if (n_ < 2 || n_ > kMaxModules) {
    throw ProcedureConfigError("", "the calibration procedure needs 2 to " +
                                       std::to_string(kMaxModules) + " modules, the model has " +
                                       std::to_string(n_));
  }
  if (!positive(period_s)) throw ProcedureConfigError("", "the cycle period must be positive");
  check_options(options_);
  yaw_sign_ = options_.counter_clockwise ? 1.0 : -1.0;
  free_mode_ = options_.wheel_drive == WheelDrive::kTorque ? ModuleDriveMode::kTorque
                                                           : ModuleDriveMode::kFreeSteer;
  run_timeout_s_ = options_.run_timeout_s > 0.0
                       ? options_.run_timeout_s
                       : 3.0 * options_.rotation_rad / options_.yaw_rate_radps + 5.0;

  // Plans: where the casters self-align about each pivot, and the wheel rates that agree
  // with a rotation at yaw_rate (nominal model; measured steering = true - offset).
  plans_.assign(static_cast<std::size_t>(n_) * kRunsPerModule, RunPlan{});
  for (std::uint32_t m = 0; m < n_; ++m) {
    const SwpcModuleParams& lock = nominal_.modules[m];
    for (std::uint32_t k = 0; k < kRunsPerModule; ++k) {
      RunPlan& plan = plans_[m * kRunsPerModule + k];
      plan.locked = m;
      plan.start_steer_meas_rad[m] = options_.locked_angles_meas_rad[k];
      const double phi = options_.locked_angles_meas_rad[k] + lock.steering_offset_rad;
      const double px = lock.x_m - lock.caster_offset_m * std::cos(phi);
      const double py = lock.y_m - lock.caster_offset_m * std::sin(phi);
      for (std::uint32_t i = 0; i < n_; ++i) {
        if (i == m) continue;
        const SwpcModuleParams& p = nominal_.modules[i];
        const double qx = p.x_m - px;
        const double qy = p.y_m - py;
        const double q = std::hypot(qx, qy);
        if (!(q > 1.5 * p.caster_offset_m)) {
          throw ProcedureConfigError("locked_angles_meas_rad",
                                     "module " + std::to_string(i + 1) +
                                         " is too close to module " + std::to_string(m + 1) +
                                         "'s pivot to self-align about it");
        }
        // Self-aligned: heading u with u . q = d, turned towards the direction of travel.
        const double heading = std::atan2(qy, qx) + yaw_sign_ * std::acos(p.caster_offset_m / q);
        plan.start_steer_meas_rad[i] = wrap_angle(heading - p.steering_offset_rad);
        const double lever = std::sqrt(q * q - p.caster_offset_m * p.caster_offset_m);
        plan.wheel_rate_radps[i] = lever * options_.yaw_rate_radps / p.wheel_radius_m;
        if (plan.wheel_rate_radps[i] > options_.max_wheel_rate_radps) {
          throw ProcedureConfigError("yaw_rate_radps",
                                     "module " + std::to_string(i + 1) + " would need " +
                                         std::to_string(plan.wheel_rate_radps[i]) +
                                         " rad/s, above max_wheel_rate_radps");
        }
      }
    }
  }

  // At most one sample per cycle; the motion-capture rate (with margin for jitter) when
  // it is slower.
  const double rate_hz = std::min(1.5 * nominal_.sensors.motion_capture.rate_hz, 1.0 / period_s);
  capacity_ = static_cast<std::size_t>(std::ceil(run_timeout_s_ * rate_hz)) + 16;
  runs_.assign(plans_.size(), RunBuffer{});
  for (RunBuffer& run : runs_) {
    for (auto* series : {&run.t_s, &run.x_m, &run.y_m, &run.yaw_rad})
      series->assign(capacity_, 0.0);
    run.wheel_rad.assign(capacity_ * n_, 0.0);
    run.steer_rad.assign(capacity_ * n_, 0.0);
  }
}

double CalibrationProcedure::run_fraction() const noexcept {
  switch (phase_) {
    case CalibrationPhase::kSettling: return 0.05;
    case CalibrationPhase::kRecording:
      return 0.05 + 0.9 * std::clamp(travel_rad_ * yaw_sign_ / options_.rotation_rad, 0.0, 1.0);
    case CalibrationPhase::kStopping: return 0.95;
    default: return 0.0;
  }
}

CalibrationProgress CalibrationProcedure::progress() const noexcept {
  CalibrationProgress p;
  const std::size_t run = std::min(run_, plans_.size() - 1);
  p.module = static_cast<std::uint32_t>(run / kRunsPerModule);
  p.run = static_cast<std::uint32_t>(run % kRunsPerModule);
  p.module_count = n_;
  p.runs_per_module = kRunsPerModule;
  p.phase = phase_;
  p.fraction = finished() ? 1.0
                          : std::clamp((static_cast<double>(run_) + run_fraction()) /
                                           static_cast<double>(plans_.size()),
                                       0.0, 1.0);
  return p;
}

void CalibrationProcedure::enter(CalibrationPhase phase, double now_s) noexcept {
  phase_ = phase;
  phase_start_s_ = now_s;
  aligned_since_s_ = -1.0;
}

Status CalibrationProcedure::fail(const char* reason, ActuatorCommand& out) noexcept {
  last_error_ = reason;
  phase_ = CalibrationPhase::kFailed;
  out = ActuatorCommand{};
  out.module_count = n_;
  return Status::kError;
}

void CalibrationProcedure::drive(const RunPlan& plan, bool wheels_on,
                                 ActuatorCommand& out) const noexcept {
  for (std::uint32_t i = 0; i < n_; ++i) {
    out.steer_rate_radps[i] = 0.0;
    if (i == plan.locked) {
      out.mode[i] = ModuleDriveMode::kLocked;
      out.wheel_rate_radps[i] = 0.0;
    } else {
      out.mode[i] = free_mode_;
      out.wheel_rate_radps[i] = wheels_on ? plan.wheel_rate_radps[i] : 0.0;
    }
  }
}

Status CalibrationProcedure::record(const HardwareState& readings) noexcept {
  const MotionCaptureSample& mc = readings.motion_capture;
  if (!mc.valid) {
    return readings.stamp_s - last_sample_s_ > options_.motion_capture_timeout_s ? Status::kError
                                                                                 : Status::kOk;
  }
  RunBuffer& run = runs_[run_];
  if (run.count >= capacity_) return Status::kError;
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
    // Steering encoders may wrap to (-pi, pi]: unwrapped against the run's previous sample, as
    // calibration_io does for a log, so that a module locked near +-pi neither averages to 0
    // nor seems to move a whole turn.
    const double steer = readings.steer_angle_rad[i];
    run.steer_rad[k * n_ + i] =
        k == 0 ? steer : unwrap_near(steer, run.steer_rad[(k - 1) * n_ + i]);
  }
  run.locked_steer_sum_rad += run.steer_rad[k * n_ + plans_[run_].locked];
  run.count = k + 1;
  last_sample_s_ = readings.stamp_s;
  return Status::kOk;
}

Status CalibrationProcedure::step(const HardwareState& readings, ActuatorCommand& out) noexcept {
  out = ActuatorCommand{};
  out.module_count = n_;
  if (phase_ == CalibrationPhase::kFailed) return Status::kError;
  if (phase_ == CalibrationPhase::kDone) return Status::kOk;
  if (readings.module_count != n_) return fail("readings have a different module count", out);
  const double now_s = readings.stamp_s;
  if (phase_ == CalibrationPhase::kIdle) enter(CalibrationPhase::kAligning, now_s);
  const RunPlan& plan = plans_[run_];
  const double in_phase_s = now_s - phase_start_s_;

  switch (phase_) {
    case CalibrationPhase::kAligning: {
      bool aligned = true;
      for (std::uint32_t i = 0; i < n_; ++i) {
        const double error = wrap_angle(plan.start_steer_meas_rad[i] - readings.steer_angle_rad[i]);
        aligned = aligned && std::abs(error) <= options_.align_tolerance_rad;
        out.mode[i] = ModuleDriveMode::kVelocity;
        out.wheel_rate_radps[i] = 0.0;
        out.steer_rate_radps[i] =
            std::clamp(options_.steer_gain_per_s * error, -options_.max_steer_rate_radps,
                       options_.max_steer_rate_radps);
      }
      if (!aligned) {
        aligned_since_s_ = -1.0;
      } else if (aligned_since_s_ < 0.0) {
        aligned_since_s_ = now_s;
      }
      if (aligned && now_s - aligned_since_s_ >= options_.align_hold_s) {
        enter(CalibrationPhase::kSettling, now_s);
        drive(plan, true, out);
      } else if (in_phase_s > options_.align_timeout_s) {
        return fail("steering did not reach the start angles within align_timeout_s", out);
      }
      return Status::kOk;
    }
    case CalibrationPhase::kSettling:
      drive(plan, true, out);
      if (in_phase_s >= options_.settle_s) {
        enter(CalibrationPhase::kRecording, now_s);
        runs_[run_].count = 0;
        runs_[run_].locked_steer_sum_rad = 0.0;
        last_sample_s_ = now_s;
        travel_rad_ = 0.0;
      }
      return Status::kOk;
    case CalibrationPhase::kRecording: {
      drive(plan, true, out);
      if (record(readings) != Status::kOk) {
        return fail(runs_[run_].count >= capacity_
                        ? "more motion-capture samples than configured for"
                        : "no motion capture within motion_capture_timeout_s while recording",
                    out);
      }
      if (travel_rad_ * yaw_sign_ >= options_.rotation_rad) {
        enter(CalibrationPhase::kStopping, now_s);
        drive(plan, false, out);
      } else if (in_phase_s > run_timeout_s_) {
        return fail("the robot did not turn the requested rotation within run_timeout_s", out);
      }
      return Status::kOk;
    }
    case CalibrationPhase::kStopping:
      drive(plan, false, out);
      if (in_phase_s >= options_.stop_s) {
        ++run_;
        if (run_ >= plans_.size()) {
          run_ = plans_.size();
          enter(CalibrationPhase::kDone, now_s);
          out = ActuatorCommand{};
          out.module_count = n_;
          return Status::kOk;
        }
        enter(CalibrationPhase::kAligning, now_s);
      }
      return Status::kOk;
    default: return fail("unknown calibration phase", out);
  }
}

CalibrationInput CalibrationProcedure::input() const {
  if (!finished()) throw std::logic_error("calibration procedure: not finished");
  CalibrationInput input;
  input.module_count = n_;
  for (std::size_t j = 0; j < runs_.size(); ++j) {
    const RunBuffer& buffer = runs_[j];
    const std::size_t count = buffer.count;
    LockedRun run;
    run.locked_module = plans_[j].locked;
    run.locked_steer_meas_rad =
        count > 0 ? buffer.locked_steer_sum_rad / static_cast<double>(count) : 0.0;
    const auto head = [count](const std::vector<double>& v) {
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
  return input;
}

CalibrationResult CalibrationProcedure::analyse() const {
  return calibrate(input(), calibration_options_for(nominal_));
}

}  // namespace swivel::calibration
