// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/write_stage.hpp"

#include "swivel/rt/finite.hpp"

namespace swivel::rt {

Twist2 WriteStage::write(const WriteRequest& request, const CycleTime& time, Drivetrain& drivetrain,
                         Hardware& hardware, CommandStage& command, PluginGuard& guard,
                         LoopEvents& events, const char*& hardware_failure) noexcept {
  const double now_s = time.now_s;
  const char* thrown = nullptr;
  Twist2 applied;
  bool zeroed = request.basis == nullptr && !request.calibrating;
  if (request.calibration_ended) {
    // Stop at once rather than through the drivetrain, whose state lags behind the
    // procedure's setpoints.
    zero();
  } else if (request.basis != nullptr && !request.calibrating) {
    // The final cycle stops at once: the daemon brings the robot to rest before it.
    const Twist2 limited =
        request.final_stop ? Twist2{} : command.limit(request.target, !request.moving, time);
    const HardwareState& basis = *request.basis;
    if (guard([&] { return drivetrain.inverse(limited, basis, period_s_, setpoints_, applied); },
              thrown) != Status::kOk) {
      events.raise(FaultCode::kDrivetrainError, now_s,
                   thrown != nullptr ? thrown : drivetrain.last_error());
      zeroed = true;
    } else if (!finite(setpoints_) || !finite(applied)) {
      events.raise(FaultCode::kDrivetrainError, now_s, "non-finite setpoints");
      zeroed = true;
    } else {
      command.follow(limited, applied);
    }
  }
  if (zeroed) {
    zero();
    applied = Twist2{};
    if (request.basis != nullptr) {
      events.log(LogLevel::kWarn, LogCode::kZeroSetpointFallback, now_s,
                 "inverse kinematics failed: zero setpoints written");
    }
  }
  if (request.calibrating || zeroed || request.final_stop || request.calibration_ended) {
    command.reset(applied);  // the limits start again from what the robot was given
  }
  if (guard([&] { return hardware.write(setpoints_); }, thrown) != Status::kOk) {
    hardware_failure = thrown != nullptr ? thrown : hardware.last_error();
    events.raise(FaultCode::kHardwareError, now_s, hardware_failure);
  } else {
    last_write_zero_ = all_zero(setpoints_);
  }
  return applied;
}

void WriteStage::report_hardware_failure(const char* failure, double now_s, Hardware& hardware,
                                         PluginGuard& guard, LoopEvents& events) noexcept {
  if (failure == nullptr || hardware_in_error_) return;
  hardware_in_error_ = true;
  copy_text(failure, failure_text_);
  const char* thrown = nullptr;
  (void)guard(
      [&] {
        hardware.on_error(failure_text_.data());
        return Status::kOk;
      },
      thrown);
  events.log(LogLevel::kWarn, LogCode::kMessage, now_s, "hardware error state: on_error() called",
             0.0, 0.0, 0.0, 0.0, failure_text_.data());
}

}  // namespace swivel::rt
