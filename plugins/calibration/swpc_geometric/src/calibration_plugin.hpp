#pragma once
// The `swpc_geometric` calibration plugin: the procedure of PAPERS.md §1 as a state machine
// on the real-time loop, and the calibration maths (swivel_swpc_calibration) off it.
//
// For each module in turn and each locked angle: steer every module to its start angle
// (closed loop on the measured steering; the locked module to the locked angle, the others
// to the angle at which they are self-aligned for a rotation about the locked wheel's
// contact point), lock the module (kLocked), drive the others with free steering (kTorque,
// or kFreeSteer at constant wheel rates), let the casters settle, record every motion-capture sample
// with the same cycle's encoder readings until the robot has turned `rotation_deg`, stop,
// then the next run.
//
// The constant wheel rates come from the nominal model: r_i psi_i = L_i w, with L_i the
// distance from module i's contact point to the pivot, so that the wheels agree about the
// rotation. On velocity-controlled wheels an error of the nominal model in the ratio of
// the radii or lever arms shows as slip and biases the radii (a common scale is
// recovered); wheels in torque control, as in the paper, roll as the rotation asks, which
// is why torque is the default.
//
// params (all optional):
//   wheel_drive: torque            torque (kTorque: the wheels roll freely) | velocity
//                                  (kFreeSteer: constant wheel rates)
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
#include <cstddef>
#include <cstdint>
#include <vector>

#include "swivel/plugin/calibration.hpp"

namespace swivel::plugins {

class SwpcGeometricCalibration final : public Calibration {
 public:
  static constexpr std::uint32_t kRunsPerModule = 2;

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

  /// Samples recorded in run `run` (module-major, then angle). Off the loop, for tests.
  [[nodiscard]] std::size_t samples(std::size_t run) const { return runs_.at(run).count; }
  /// Samples each run can hold (sized in configure()).
  [[nodiscard]] std::size_t capacity() const noexcept { return capacity_; }

 private:
  // What one run commands, fixed at configure() from the nominal model.
  struct RunPlan {
    std::uint32_t locked = 0;
    std::array<double, kMaxModules> start_steer_meas_rad{};  // alignment targets
    std::array<double, kMaxModules> wheel_rate_radps{};      // free modules while driven
  };
  // Recorded data of one run; vectors sized in configure() and never grown on the loop.
  struct RunBuffer {
    std::vector<double> t_s, x_m, y_m, yaw_rad;
    std::vector<double> wheel_rad;  // sample-major: [sample * n + module]
    std::vector<double> steer_rad;
    std::size_t count = 0;
    double locked_steer_sum_rad = 0.0;
  };

  void enter(CalibrationPhase phase, double now_s) noexcept;
  Status fail(const char* reason) noexcept;
  void publish_progress(double run_fraction) noexcept;
  void drive(const RunPlan& plan, bool wheels_on, ActuatorCommand& out) const noexcept;
  Status record(const HardwareState& readings) noexcept;

  // Configuration.
  RobotModel nominal_;
  std::uint32_t n_ = 0;
  std::array<double, kRunsPerModule> locked_angles_rad_{};
  double yaw_sign_ = 1.0;
  ModuleDriveMode drive_mode_ = ModuleDriveMode::kTorque;  // how the free modules are driven
  double rotation_rad_ = 0.0;
  double settle_s_ = 1.0;
  double stop_s_ = 0.5;
  double align_tolerance_rad_ = 0.0;
  double align_hold_s_ = 0.1;
  double align_timeout_s_ = 10.0;
  double steer_gain_per_s_ = 4.0;
  double max_steer_rate_radps_ = 2.0;
  double run_timeout_s_ = 0.0;
  double mocap_timeout_s_ = 0.5;
  std::vector<RunPlan> plans_;
  std::vector<RunBuffer> runs_;
  std::size_t capacity_ = 0;

  // Loop-thread state.
  std::size_t run_ = 0;
  CalibrationPhase phase_ = CalibrationPhase::kIdle;
  double phase_start_s_ = 0.0;
  double aligned_since_s_ = -1.0;
  double last_sample_s_ = 0.0;
  double previous_yaw_rad_ = 0.0;
  double travel_rad_ = 0.0;

  // Read by other threads.
  std::atomic<std::uint32_t> progress_run_{0};
  std::atomic<CalibrationPhase> progress_phase_{CalibrationPhase::kIdle};
  std::atomic<double> progress_fraction_{0.0};
  std::atomic<bool> finished_{false};
  std::atomic<bool> failed_{false};
  std::atomic<const char*> last_error_{""};
};

}  // namespace swivel::plugins
