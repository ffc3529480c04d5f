// SPDX-License-Identifier: Apache-2.0
#include "swivel/calibration/simulated_procedure.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "swivel/pose_math.hpp"

namespace swivel::calibration {

SimulatedCalibration run_simulated_calibration(const RobotModel& nominal, const RobotModel& truth,
                                               const SimulatedProcedureOptions& options) {
  if (nominal.drivetrain != DrivetrainKind::kSwpc || truth.drivetrain != DrivetrainKind::kSwpc ||
      nominal.modules.size() != truth.modules.size()) {
    throw std::invalid_argument(
        "simulated calibration: nominal and true models must be swpc robots with the same "
        "module count");
  }
  if (!(options.loop_rate_hz > 0.0) || !std::isfinite(options.loop_rate_hz)) {
    throw std::invalid_argument("simulated calibration: the loop rate must be positive");
  }
  const double dt_s = 1.0 / options.loop_rate_hz;
  CalibrationProcedure procedure(nominal, options.procedure, dt_s);
  sim::World world(truth, options.sim);

  // The procedure ends itself (done, or failed on one of its timeouts); the bound only
  // guards against a procedure that never does.
  const ProcedureOptions& o = options.procedure;
  const double run_s =
      o.align_timeout_s + o.settle_s + o.stop_s +
      (o.run_timeout_s > 0.0 ? o.run_timeout_s : 3.0 * o.rotation_rad / o.yaw_rate_radps + 5.0);
  const auto max_cycles = static_cast<std::int64_t>(
      std::ceil(2.0 * run_s * static_cast<double>(nominal.modules.size()) *
                CalibrationProcedure::kRunsPerModule / dt_s));

  HardwareState reading;
  ActuatorCommand command;
  std::int64_t cycle = 0;
  while (!procedure.finished()) {
    world.read(reading);
    reading.stamp_s = static_cast<double>(cycle) * dt_s;  // the loop's clock
    // Up or down by the seventh of the cycle count: irregular at any sampling rate.
    const double flicker =
        (cycle / 7) % 2 == 0 ? options.steering_flicker_rad : -options.steering_flicker_rad;
    for (double& a : reading.steer_angle_rad) {
      a += flicker;
      if (options.wrap_steering) {
        const double c = options.steering_wrap_center_rad;
        a = c + wrap_pi(a - c);
      }
    }
    if (procedure.step(reading, command) != Status::kOk) {
      throw std::runtime_error(std::string("simulated calibration: ") + procedure.last_error());
    }
    if (world.step(dt_s, command) != Status::kOk) {
      throw std::runtime_error(std::string("simulated calibration: ") + world.last_error());
    }
    if (++cycle > max_cycles) {
      throw std::runtime_error("simulated calibration: the procedure did not end");
    }
  }
  SimulatedCalibration out;
  out.input = procedure.input();
  out.result = procedure.analyse();
  out.duration_s = static_cast<double>(cycle) * dt_s;
  return out;
}

}  // namespace swivel::calibration
