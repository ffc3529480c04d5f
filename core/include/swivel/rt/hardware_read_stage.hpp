// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's first stage: read the hardware and validate the reading, so that the stages after
// it see either a usable reading or none. A read that fails or throws, or a module count out
// of range, is kHardwareError; a non-finite value (after a configured external gyro replaced
// the reading's) is kNonFiniteSensor. The external sensors are taken around the read in their
// fixed order (gyro before, motion capture and staleness after). The stage keeps the previous
// usable reading for the odometry.
//
// Loop thread only. Real-time safe: no allocation, no lock, no I/O; noexcept (a throwing
// plugin is stopped by the PluginGuard).

#include "swivel/plugin/hardware.hpp"
#include "swivel/rt/external_sensor_stage.hpp"
#include "swivel/rt/loop_events.hpp"
#include "swivel/rt/plugin_guard.hpp"
#include "swivel/types.hpp"

namespace swivel::rt {

/// The first non-finite field of a reading, as a static cause text; nullptr when all finite.
const char* non_finite_field(const HardwareState& reading) noexcept;

/// One cycle's read.
struct ReadOutcome {
  bool ok = false;                ///< current() is a usable reading
  const char* failure = nullptr;  ///< the hardware fault's cause (a read failure), else null
};

class HardwareReadStage {
 public:
  /// Reads into current() and validates it, raising the fault of a failed or invalid read.
  ReadOutcome read(double now_s, Hardware& hardware, ExternalSensorStage& sensors,
                   PluginGuard& guard, LoopEvents& events) noexcept;

  /// At the end of a cycle: a usable reading becomes the previous one.
  void end_cycle(bool reading_ok) noexcept {
    if (!reading_ok) return;
    previous_ = current_;
    has_previous_ = true;
  }

  /// The next reading starts the odometry afresh (the last one is from before a pause).
  void forget_previous() noexcept { has_previous_ = false; }

  [[nodiscard]] const HardwareState& current() const noexcept { return current_; }
  [[nodiscard]] const HardwareState& previous() const noexcept { return previous_; }
  [[nodiscard]] bool has_previous() const noexcept { return has_previous_; }

 private:
  HardwareState current_{};
  HardwareState previous_{};
  bool has_previous_ = false;
};

}  // namespace swivel::rt
