// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's calibration stage: a calibration procedure handed over from its own thread drives
// the actuators in place of the velocity command, from the cycle boundary it is taken at until
// it finishes, fails, is cancelled or a fault stops it. Instances cross threads through atomic
// slots (pending, active, retired) so that neither side waits; the calibrating thread takes a
// finished instance back and destroys it off the loop. A calibration taken while a fault is
// latched or the loop is stopping is handed back refused. Whenever one starts or ends, the
// velocity command seen before is dropped: only a fresh one moves the robot afterwards.
//
// The calibrating thread calls start(), cancel(), take_finished(); the loop thread
// take_pending() and step(); any thread in_flight() and active(). Real-time safe: no
// allocation, no lock, no I/O; noexcept (the procedure is called through the PluginGuard).

#include <atomic>
#include <cstdint>

#include "swivel/plugin/calibration.hpp"
#include "swivel/rt/command_stage.hpp"
#include "swivel/rt/loop_events.hpp"
#include "swivel/rt/plugin_guard.hpp"

namespace swivel::rt {

/// How a calibration handed back by the loop ended.
enum class CalibrationOutcome : std::uint8_t {
  kNone = 0,       ///< nothing handed back
  kFinished = 1,   ///< every run recorded: analyse it
  kFailed = 2,     ///< the procedure or another fault stopped it
  kCancelled = 3,  ///< cancel_calibration() or the loop stopping
  kRefused = 4,    ///< a fault was latched when the loop would have started it
};

class CalibrationStage {
 public:
  /// The calibrating thread (ControlLoop::start_calibration()).
  bool start(Calibration* calibration) noexcept;
  /// The calibrating thread (ControlLoop::cancel_calibration()).
  void cancel() noexcept;
  /// The calibrating thread (ControlLoop::take_finished_calibration()).
  Calibration* take_finished(CalibrationOutcome* outcome) noexcept;

  /// Any thread. True from start() until the instance is taken back.
  [[nodiscard]] bool in_flight() const noexcept {
    return in_flight_.load(std::memory_order_acquire);
  }
  /// Any thread. The calibration the loop is running, or nullptr.
  [[nodiscard]] Calibration* active() const noexcept {
    return active_.load(std::memory_order_acquire);
  }

  /// Loop thread, at the cycle boundary: takes a pending calibration (refused while a fault
  /// is latched or the loop is `stopping`).
  void take_pending(double now_s, bool stopping, CommandStage& command,
                    LoopEvents& events) noexcept;

  /// Loop thread. One cycle of the active calibration into `setpoints` from `reading`. True
  /// while it drives the actuators this cycle; false when there is none or it ended this
  /// cycle (`final_stop` cancels it).
  bool step(double now_s, bool final_stop, const HardwareState& reading, std::uint32_t module_count,
            ActuatorCommand& setpoints, CommandStage& command, PluginGuard& guard,
            LoopEvents& events) noexcept;

 private:
  void retire(CalibrationOutcome outcome, double now_s, CommandStage& command,
              LoopEvents& events) noexcept;

  std::atomic<Calibration*> pending_{nullptr};
  std::atomic<Calibration*> active_{nullptr};  // written by the loop only
  std::atomic<Calibration*> retired_{nullptr};
  std::atomic<CalibrationOutcome> retired_outcome_{CalibrationOutcome::kNone};
  std::atomic<bool> in_flight_{false};  // written by the calibrating thread
  std::atomic<bool> cancel_{false};
};

}  // namespace swivel::rt
