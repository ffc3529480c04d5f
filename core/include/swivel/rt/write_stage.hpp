// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's write stage: from the cycle's target twist to the setpoints the hardware gets.
// The twist is limited (CommandStage), turned into module setpoints by the drivetrain's
// inverse kinematics and written; a calibration fills the setpoints itself. When there is no
// basis for the kinematics (no reading yet), the drivetrain refuses or gives a non-finite
// result (kDrivetrainError), zero setpoints are written instead, and so they are when a
// calibration ended this cycle. A failed write is kHardwareError; the hardware hears of its
// failure once through on_error(), at the cycle's end, until a clear.
//
// Loop thread only. Real-time safe: no allocation, no lock, no I/O; noexcept (plugins are
// called through the PluginGuard).

#include <array>
#include <cstdint>

#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/rt/command_stage.hpp"
#include "swivel/rt/loop_events.hpp"
#include "swivel/rt/plugin_guard.hpp"

namespace swivel::rt {

/// What the cycle asks of the write stage.
struct WriteRequest {
  const HardwareState* basis = nullptr;  ///< the newest usable reading, null when none
  Twist2 target;                         ///< the twist asked for (zero unless moving)
  bool moving = false;                   ///< towards a command (else the stop's limits)
  bool calibrating = false;              ///< a calibration filled setpoints() this cycle
  bool calibration_ended = false;        ///< a calibration ended this cycle
  bool final_stop = false;               ///< the loop's last cycle: zero at once
};

class WriteStage {
 public:
  /// `period_s`: the loop's, for which each setpoint holds.
  WriteStage(std::uint32_t module_count, double period_s) noexcept
      : module_count_(module_count), period_s_(period_s) {}

  /// The setpoints to write (a calibration fills them before write()).
  [[nodiscard]] ActuatorCommand& setpoints() noexcept { return setpoints_; }

  /// Computes and writes the cycle's setpoints; returns the twist applied (zero when zero
  /// setpoints were written). A failed write sets `hardware_failure` to its cause.
  Twist2 write(const WriteRequest& request, const CycleTime& time, Drivetrain& drivetrain,
               Hardware& hardware, CommandStage& command, PluginGuard& guard, LoopEvents& events,
               const char*& hardware_failure) noexcept;

  /// At the cycle's end: on_error() once for a hardware failure of this cycle (`failure`,
  /// null when none), until clear_hardware_error(). `failure` may point into the guard's
  /// buffer (what a plugin threw): it is copied before the guarded on_error() call reuses it.
  void report_hardware_failure(const char* failure, double now_s, Hardware& hardware,
                               PluginGuard& guard, LoopEvents& events) noexcept;

  /// The latched fault was cleared: the next hardware failure is reported again.
  void clear_hardware_error() noexcept { hardware_in_error_ = false; }

  /// The hardware is in its error state (on_error() called).
  [[nodiscard]] bool hardware_in_error() const noexcept { return hardware_in_error_; }

  /// The last setpoints written were all zero.
  [[nodiscard]] bool last_write_zero() const noexcept { return last_write_zero_; }

 private:
  void zero() noexcept {
    setpoints_ = ActuatorCommand{};
    setpoints_.module_count = module_count_;
  }

  std::uint32_t module_count_;
  double period_s_;
  ActuatorCommand setpoints_{};
  bool last_write_zero_ = true;
  bool hardware_in_error_ = false;
  std::array<char, sizeof(FaultDetail)> failure_text_{};  // the failure on_error() is given
};

}  // namespace swivel::rt
