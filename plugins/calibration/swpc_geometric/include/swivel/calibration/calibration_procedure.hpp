// SPDX-License-Identifier: Apache-2.0
#pragma once
// The calibration procedure of docs/methods.md §1 as a state machine stepped once per control
// cycle: what the daemon's `swpc_geometric` plugin runs on the real-time loop and what the
// offline simulated calibration (simulated_procedure.hpp) runs on the simulated world, so
// that both record the same runs and hand them to the same analysis.
//
// For each module in turn and each locked angle: steer every module to its start angle
// (closed loop on the measured steering; the locked module to the locked angle, the others
// to the angle at which they are self-aligned for a rotation about the locked wheel's
// contact point), lock the module (kLocked), drive the others with free steering, let the
// casters settle, record every motion-capture sample with the same cycle's encoder readings
// until the robot has turned `rotation_rad`, stop, then the next run.
//
// The free wheels' setpoints come from the nominal model: r_i psi_i = L_i w, with L_i the
// distance from module i's contact point to the pivot. In torque drive (kTorque, as in the
// paper) they only set the pace and each wheel rolls as the rotation asks, so every radius
// is observable. In velocity drive (kFreeSteer) the wheels track those rates: an error of
// the nominal model in the ratio of radii or lever arms shows as slip, and each radius is
// pulled towards the common mean (a common scale is still recovered).
//
// Plain code: no threads, DDS or YAML. Construction and input() allocate; step() and the
// accessors are real-time safe.

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "swivel/calibration/swpc_calibration.hpp"
#include "swivel/plugin/calibration.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::calibration {

/// How the free modules' wheels are driven while the robot turns about the locked one.
enum class WheelDrive : std::uint8_t {
  kTorque,    ///< constant torque: the wheel rolls as the rotation asks (the paper)
  kVelocity,  ///< constant wheel rates from the nominal model; wrong ratios slip
};

struct ProcedureOptions {
  /// Measured steering angles of the locked module; the first run of each module is P1.
  std::array<double, 2> locked_angles_meas_rad = {0.7853981633974483, 2.8797932657906435};
  double yaw_rate_radps = 0.3;  ///< rotation rate the wheel setpoints are chosen for
  bool counter_clockwise = true;
  /// Rotation recorded per run. The steering offset is only as good as the pivot over the
  /// caster offset (0.05 mm / 20 mm = 0.14 deg), and a long arc fixes the pivot best.
  double rotation_rad = 5.235987755982989;  // 300 deg
  double settle_s = 1.0;                    ///< driven before recording starts (casters self-align)
  double stop_s = 0.5;                      ///< wheels at zero between runs
  double align_tolerance_rad = 0.008726646259971648;  ///< 0.5 deg
  double align_hold_s = 0.1;                          ///< held within tolerance before locking
  double align_timeout_s = 10.0;
  double steer_gain_per_s = 4.0;  ///< alignment: steering rate = gain * angle error
  double max_steer_rate_radps = 2.0;
  double max_wheel_rate_radps = 30.0;  ///< refuses a plan asking more of a wheel
  /// Recording must end within this; <= 0: 3 * rotation / yaw rate + 5 s.
  double run_timeout_s = 0.0;
  double motion_capture_timeout_s = 0.5;  ///< longest gap while recording
  WheelDrive wheel_drive = WheelDrive::kTorque;
};

/// A procedure that cannot run with these options on this robot; option() names the
/// ProcedureOptions field (as the plugin's parameter is named) that should change.
class ProcedureConfigError : public std::invalid_argument {
 public:
  ProcedureConfigError(std::string option, const std::string& what)
      : std::invalid_argument(what), option_(std::move(option)) {}
  [[nodiscard]] const std::string& option() const noexcept { return option_; }

 private:
  std::string option_;
};

class CalibrationProcedure {
 public:
  static constexpr std::uint32_t kRunsPerModule = 2;

  /// Plans every run from the nominal model and sizes the recording storage for cycles of
  /// `period_s` (at most one sample per cycle, or per motion-capture sample when slower).
  /// Not real-time safe. @throws ProcedureConfigError.
  CalibrationProcedure(RobotModel nominal, const ProcedureOptions& options, double period_s);

  /// Real-time safe. One cycle: `readings` in, every module's setpoints and drive mode out.
  /// kError when the procedure cannot go on (last_error() says why; `out` then commands zero).
  Status step(const HardwareState& readings, ActuatorCommand& out) noexcept;

  /// Real-time safe.
  [[nodiscard]] CalibrationProgress progress() const noexcept;
  [[nodiscard]] bool finished() const noexcept { return phase_ == CalibrationPhase::kDone; }
  [[nodiscard]] bool failed() const noexcept { return phase_ == CalibrationPhase::kFailed; }
  /// A static message describing the failure ("" before one).
  [[nodiscard]] const char* last_error() const noexcept { return last_error_; }

  /// Samples recorded in run `run` (module-major, then angle).
  [[nodiscard]] std::size_t samples(std::size_t run) const { return runs_.at(run).count; }
  /// Samples each run can hold.
  [[nodiscard]] std::size_t capacity() const noexcept { return capacity_; }
  [[nodiscard]] const RobotModel& nominal() const noexcept { return nominal_; }

  /// Not real-time safe. The recorded runs as the calibration's input (P1, P2 per module).
  /// @throws std::logic_error unless finished().
  [[nodiscard]] CalibrationInput input() const;

  /// Not real-time safe. The analysis every caller of the procedure uses: calibrate() on
  /// input() with the thresholds and encoder noise of the nominal model.
  /// @throws std::logic_error unless finished().
  [[nodiscard]] CalibrationResult analyse() const;

 private:
  // What one run commands, fixed at construction from the nominal model.
  struct RunPlan {
    std::uint32_t locked = 0;
    std::array<double, kMaxModules> start_steer_meas_rad{};  // alignment targets
    std::array<double, kMaxModules> wheel_rate_radps{};      // free modules while driven
  };
  // Recorded data of one run; sized at construction and never grown by step().
  struct RunBuffer {
    std::vector<double> t_s, x_m, y_m, yaw_rad;
    std::vector<double> wheel_rad;  // sample-major: [sample * n + module]
    std::vector<double> steer_rad;
    std::size_t count = 0;
    double locked_steer_sum_rad = 0.0;
  };

  void enter(CalibrationPhase phase, double now_s) noexcept;
  Status fail(const char* reason, ActuatorCommand& out) noexcept;
  void drive(const RunPlan& plan, bool wheels_on, ActuatorCommand& out) const noexcept;
  Status record(const HardwareState& readings) noexcept;
  [[nodiscard]] double run_fraction() const noexcept;

  RobotModel nominal_;
  std::uint32_t n_ = 0;
  ProcedureOptions options_;
  double yaw_sign_ = 1.0;
  ModuleDriveMode free_mode_ = ModuleDriveMode::kTorque;
  double run_timeout_s_ = 0.0;
  std::vector<RunPlan> plans_;
  std::vector<RunBuffer> runs_;
  std::size_t capacity_ = 0;

  std::size_t run_ = 0;
  CalibrationPhase phase_ = CalibrationPhase::kIdle;
  double phase_start_s_ = 0.0;
  double aligned_since_s_ = -1.0;
  double last_sample_s_ = 0.0;
  double previous_yaw_rad_ = 0.0;
  double travel_rad_ = 0.0;
  const char* last_error_ = "";
};

}  // namespace swivel::calibration
