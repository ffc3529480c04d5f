// SPDX-License-Identifier: Apache-2.0
#pragma once
// The `swpc_geometric` calibration plugin: a thin adapter that reads its parameters, runs the
// calibration procedure of docs/methods.md §1 (calibration_procedure.hpp, the same state machine
// the offline simulated calibration runs) on the real-time loop, publishes its progress to
// other threads, and hands the recorded runs to the calibration maths off the loop.
//
// params (all optional):
//   wheel_drive: torque            torque (kTorque: the wheels roll as the rotation asks, as
//                                  in the paper) | velocity (kFreeSteer: constant wheel
//                                  rates from the nominal model; wrong ratios slip)
//   locked_angles_deg: [45, 165]   measured steering angles of the locked module, two
//   yaw_rate_radps: 0.3            robot rotation rate the wheel rates are chosen for
//   direction: ccw                 ccw | cw
//   rotation_deg: 300              rotation recorded per run: the steering offset's error is
//                                  the pivot's over the caster offset (0.05 mm / 20 mm =
//                                  0.14 deg), and a long arc fixes the pivot best
//   settle_s: 1.0                  driven before recording starts (casters self-align)
//   stop_s: 0.5                    wheels at zero between runs
//   align_tolerance_deg: 0.5       steering alignment tolerance
//   align_hold_s: 0.1              held within tolerance before locking
//   align_timeout_s: 10            alignment must finish within this
//   steer_gain_per_s: 4            alignment: steering rate = gain * angle error
//   max_steer_rate_radps: 2.0      alignment steering rate limit
//   max_wheel_rate_radps: 30       refuses a configuration asking more of a wheel
//   run_timeout_s: 3 * rotation / yaw_rate + 5   recording must end within this
//   motion_capture_timeout_s: 0.5  longest gap between motion-capture samples while
//                                  recording

#include <atomic>
#include <cstdint>
#include <optional>

#include "swivel/calibration/calibration_procedure.hpp"
#include "swivel/plugin/calibration.hpp"

namespace swivel::plugins {

class SwpcGeometricCalibration final : public Calibration {
 public:
  static constexpr std::uint32_t kRunsPerModule = calibration::CalibrationProcedure::kRunsPerModule;

  void configure(const PluginContext& ctx) override;
  Status step(const HardwareState& readings, ActuatorCommand& out) noexcept override;
  [[nodiscard]] CalibrationProgress progress() const noexcept override;
  [[nodiscard]] bool finished() const noexcept override {
    return finished_.load(std::memory_order_acquire);
  }
  [[nodiscard]] bool failed() const noexcept override {
    return failed_.load(std::memory_order_acquire);
  }
  /// Off the loop. Refuses (ok false) when the procedure did not finish.
  CalibrationReport analyse() override;
  [[nodiscard]] const char* last_error() const noexcept override {
    return last_error_.load(std::memory_order_acquire);
  }

 private:
  void publish() noexcept;

  std::optional<calibration::CalibrationProcedure> procedure_;  // loop thread only

  // Read by other threads.
  std::atomic<std::uint32_t> progress_run_{0};
  std::atomic<std::uint32_t> module_count_{0};
  std::atomic<CalibrationPhase> progress_phase_{CalibrationPhase::kIdle};
  std::atomic<double> progress_fraction_{0.0};
  std::atomic<bool> finished_{false};
  std::atomic<bool> failed_{false};
  std::atomic<const char*> last_error_{""};
};

}  // namespace swivel::plugins
