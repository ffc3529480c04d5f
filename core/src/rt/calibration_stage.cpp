// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/calibration_stage.hpp"

#include "swivel/rt/finite.hpp"

namespace swivel::rt {

bool CalibrationStage::start(Calibration* calibration) noexcept {
  if (calibration == nullptr) return false;
  if (in_flight_.load(std::memory_order_acquire)) return false;
  in_flight_.store(true, std::memory_order_release);
  cancel_.store(false, std::memory_order_release);
  pending_.store(calibration, std::memory_order_release);
  return true;
}

void CalibrationStage::cancel() noexcept {
  if (!in_flight_.load(std::memory_order_acquire)) return;
  // Not taken by the loop yet: hand it back directly. At most one instance is in flight,
  // so the retire slot is empty and the loop will never see this one.
  if (Calibration* pending = pending_.exchange(nullptr, std::memory_order_acq_rel)) {
    retired_outcome_.store(CalibrationOutcome::kCancelled, std::memory_order_relaxed);
    retired_.store(pending, std::memory_order_release);
    return;
  }
  cancel_.store(true, std::memory_order_release);
}

Calibration* CalibrationStage::take_finished(CalibrationOutcome* outcome) noexcept {
  Calibration* retired = retired_.exchange(nullptr, std::memory_order_acq_rel);
  if (retired == nullptr) return nullptr;
  if (outcome != nullptr) *outcome = retired_outcome_.load(std::memory_order_relaxed);
  cancel_.store(false, std::memory_order_release);
  in_flight_.store(false, std::memory_order_release);
  return retired;
}

void CalibrationStage::take_pending(double now_s, bool stopping, CommandStage& command,
                                    LoopEvents& events) noexcept {
  if (active_.load(std::memory_order_relaxed) != nullptr) return;
  Calibration* next = pending_.exchange(nullptr, std::memory_order_acq_rel);
  if (next == nullptr) return;
  active_.store(next, std::memory_order_release);
  if (events.any_latched() || stopping) {
    // A robot in safe stop must be cleared before anything moves it; one shutting down stays.
    retire(CalibrationOutcome::kRefused, now_s, command, events);
    return;
  }
  command.drop();
  events.log(LogLevel::kInfo, LogCode::kMessage, now_s, "calibration started");
}

void CalibrationStage::retire(CalibrationOutcome outcome, double now_s, CommandStage& command,
                              LoopEvents& events) noexcept {
  Calibration* outgoing = active_.load(std::memory_order_relaxed);
  if (outgoing == nullptr) return;
  retired_outcome_.store(outcome, std::memory_order_relaxed);
  // start() refuses while an instance is in flight, so the slot is empty here.
  retired_.store(outgoing, std::memory_order_release);
  active_.store(nullptr, std::memory_order_release);
  command.drop();  // only a command sent after the calibration moves the robot
  events.log(outcome == CalibrationOutcome::kFinished ? LogLevel::kInfo : LogLevel::kWarn,
             LogCode::kMessage, now_s,
             outcome == CalibrationOutcome::kFinished    ? "calibration finished"
             : outcome == CalibrationOutcome::kCancelled ? "calibration cancelled"
             : outcome == CalibrationOutcome::kRefused
                 ? "calibration refused: fault latched or stopping"
                 : "calibration stopped by a fault");
}

bool CalibrationStage::step(double now_s, bool final_stop, const HardwareState& reading,
                            std::uint32_t module_count, ActuatorCommand& setpoints,
                            CommandStage& command, PluginGuard& guard,
                            LoopEvents& events) noexcept {
  Calibration* calibration = active_.load(std::memory_order_relaxed);
  if (calibration == nullptr) return false;
  if (final_stop || cancel_.exchange(false, std::memory_order_acq_rel)) {
    retire(CalibrationOutcome::kCancelled, now_s, command, events);
    if (!final_stop) {
      events.raise_transient(FaultCode::kCalibrationError, now_s, "calibration cancelled");
    }
    return false;
  }
  if (events.any_latched()) {
    retire(CalibrationOutcome::kFailed, now_s, command, events);
    return false;
  }
  const char* thrown = nullptr;
  const Status status = guard([&] { return calibration->step(reading, setpoints); }, thrown);
  if (status != Status::kOk) {
    events.raise(FaultCode::kCalibrationError, now_s,
                 thrown != nullptr ? thrown : calibration->last_error());
  } else if (setpoints.module_count != module_count || !finite(setpoints)) {
    events.raise(FaultCode::kCalibrationError, now_s, "invalid calibration setpoints");
  } else if (calibration->failed()) {
    events.raise(FaultCode::kCalibrationError, now_s, calibration->last_error());
  } else if (calibration->finished()) {
    retire(CalibrationOutcome::kFinished, now_s, command, events);
    return false;
  } else {
    return true;
  }
  retire(CalibrationOutcome::kFailed, now_s, command, events);
  return false;
}

}  // namespace swivel::rt
