// SPDX-License-Identifier: Apache-2.0
#pragma once
// Calibration plugin: a procedure that the real-time loop runs instead of the velocity path
// (LoopMode::kCalibration). Each cycle step() turns the readings into actuator setpoints,
// written to the hardware as they are (the drivetrain's inverse kinematics is bypassed), and
// records what the analysis needs into storage sized in configure(). When the procedure
// has finished the loop hands the instance back, and analyse() computes the calibrated
// robot model off the loop.

#include <cstdint>
#include <string>
#include <vector>

#include "swivel/plugin/abi.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel {

/// Where a procedure is.
enum class CalibrationPhase : std::uint8_t {
  kIdle = 0,       ///< configured, no step yet
  kAligning = 1,   ///< steering the modules to the run's start angles
  kSettling = 2,   ///< locked module held, the others driven; not yet recording
  kRecording = 3,  ///< recording motion capture and encoders
  kStopping = 4,   ///< wheels stopped before the next run
  kDone = 5,       ///< every run recorded; step() commands zero
  kFailed = 6,     ///< stopped on an error (last_error() says which)
};

/// "aligning", "recording", ... for messages.
inline const char* calibration_phase_name(CalibrationPhase phase) noexcept {
  switch (phase) {
    case CalibrationPhase::kIdle: return "idle";
    case CalibrationPhase::kAligning: return "aligning";
    case CalibrationPhase::kSettling: return "settling";
    case CalibrationPhase::kRecording: return "recording";
    case CalibrationPhase::kStopping: return "stopping";
    case CalibrationPhase::kDone: return "done";
    case CalibrationPhase::kFailed: return "failed";
  }
  return "unknown";
}

/// Progress of a procedure (trivially copyable).
struct CalibrationProgress {
  std::uint32_t module = 0;  ///< 0-based module the current run locks
  std::uint32_t module_count = 0;
  std::uint32_t run = 0;  ///< 0-based run of that module (locked angle index)
  std::uint32_t runs_per_module = 0;
  double fraction = 0.0;  ///< of the whole procedure, [0, 1]
  CalibrationPhase phase = CalibrationPhase::kIdle;
};

/// One-sigma uncertainties of one module's calibrated parameters.
struct SwpcModuleUncertainty {
  double x_m = 0.0;
  double y_m = 0.0;
  double steering_offset_rad = 0.0;
  double caster_offset_m = 0.0;
  double wheel_radius_m = 0.0;
};

/// What analyse() found: a calibrated model, or a refusal with its reason.
struct CalibrationReport {
  bool ok = false;
  std::string verdict;  ///< one line per quality check ("PASS name: ..." / "FAIL name: ...")
  std::string reason;   ///< why it refused (empty when ok)
  RobotModel model;     ///< the nominal model with the calibrated parameters (when ok)
  std::vector<SwpcModuleUncertainty> uncertainty;  ///< per module (when ok)
};

class Calibration {
 public:
  virtual ~Calibration() = default;

  /// Off the loop. Reads ctx.params, takes the nominal geometry from ctx.robot and sizes
  /// all recording storage from ctx.period_s, the motion-capture rate and the durations.
  /// @throws ConfigError naming the key.
  virtual void configure(const PluginContext& ctx) = 0;

  /// Real-time safe. One cycle of the procedure: `readings` are this cycle's (finite)
  /// sensor readings; `out` receives every module's setpoints and drive mode. kError when
  /// the procedure cannot go on (last_error() says why); the host then stops the robot.
  virtual Status step(const HardwareState& readings, ActuatorCommand& out) = 0;

  /// Any thread. Real-time safe.
  [[nodiscard]] virtual CalibrationProgress progress() const noexcept = 0;

  /// Any thread. Real-time safe. True once every run was recorded.
  [[nodiscard]] virtual bool finished() const noexcept = 0;

  /// Any thread. Real-time safe. True once the procedure stopped on an error.
  [[nodiscard]] virtual bool failed() const noexcept = 0;

  /// Off the loop, after the host let go of the instance (finished() true). Hands the
  /// recorded data to the calibration maths. May take a while; never throws on bad data
  /// (the report refuses instead). @throws std::logic_error when nothing was recorded.
  virtual CalibrationReport analyse() = 0;

  /// Any thread. Real-time safe. A static message describing the last kError.
  [[nodiscard]] virtual const char* last_error() const noexcept { return ""; }
};

}  // namespace swivel

// The fingerprint SWIVEL_EXPORT_PLUGIN puts in the descriptor; it needs this interface whole.
#include "swivel/plugin/abi_fingerprint.hpp"  // IWYU pragma: export
