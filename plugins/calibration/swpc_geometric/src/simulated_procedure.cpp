#include "swivel/calibration/simulated_procedure.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "swivel/calibration/calibration_io.hpp"
#include "swivel/sim/effects.hpp"
#include "swivel/sim/open_loop.hpp"

namespace swivel::calibration {
namespace {

RunLog simulate_run(const RobotModel& nominal, const RobotModel& truth,
                    const sim::PlantParams& plant, const SimulatedProcedureOptions& options,
                    std::size_t locked_module, double locked_meas_rad, std::uint64_t seed) {
  const double w = std::copysign(options.yaw_rate_radps, options.rotation_rad);
  const sim::CalibrationMotion motion{locked_module, locked_meas_rad, w};
  const sim::OpenLoopController controller(nominal);
  ActuatorCommand command;
  Twist2 commanded;
  if (!controller.calibration(motion, command, commanded)) {
    throw std::invalid_argument("calibration motion about module " +
                                std::to_string(locked_module + 1) +
                                " impossible: a free caster's steering axis lies within its "
                                "caster offset of the pivot");
  }
  sim::SimOptions sim_options = options.sim;
  sim_options.seed = seed;
  sim_options.initial_steer_rad = sim::calibration_steer_angles(plant, motion);
  sim::World world(truth, sim_options);

  RunLog log;
  log.source = "simulated calibration, module " + std::to_string(locked_module + 1) + " at " +
               std::to_string(locked_meas_rad) + " rad";
  log.header = run_log_header(nominal);
  log.header.comments.push_back(calibration_comment({locked_module, locked_meas_rad}, w));

  const double duration_s = std::abs(options.rotation_rad) / options.yaw_rate_radps;
  const auto steps = static_cast<std::int64_t>(std::llround(duration_s * options.rate_hz));
  const double dt_s = 1.0 / options.rate_hz;
  HardwareState reading;
  for (std::int64_t k = 0; k <= steps; ++k) {
    world.read(reading);
    reading.stamp_s = static_cast<double>(k) * dt_s;
    log.samples.push_back(sim::make_run_log_sample(reading, commanded));
    if (k == steps) break;
    if (world.step(dt_s, command) != Status::kOk) {
      throw std::invalid_argument(std::string("simulated calibration: ") + world.last_error());
    }
  }
  return log;
}

}  // namespace

std::vector<RunLog> simulate_calibration_runs(const RobotModel& nominal, const RobotModel& truth,
                                              const SimulatedProcedureOptions& options) {
  if (nominal.drivetrain != DrivetrainKind::kSwpc || truth.drivetrain != DrivetrainKind::kSwpc ||
      nominal.modules.size() != truth.modules.size()) {
    throw std::invalid_argument(
        "simulated calibration: nominal and true models must be swpc robots with the same "
        "module count");
  }
  if (!(options.yaw_rate_radps > 0.0) || !(options.rate_hz > 0.0) ||
      !(std::abs(options.rotation_rad) > 0.0) || options.locked_angles_meas_rad.empty()) {
    throw std::invalid_argument(
        "simulated calibration: need a positive yaw rate, rate and rotation, and locked angles");
  }
  const sim::PlantParams plant = sim::resolve_plant(truth);
  std::vector<RunLog> logs;
  std::uint64_t seed = options.sim.seed;
  for (std::size_t m = 0; m < nominal.modules.size(); ++m) {
    for (const double angle : options.locked_angles_meas_rad) {
      logs.push_back(simulate_run(nominal, truth, plant, options, m, angle, seed++));
    }
  }
  return logs;
}

SimulatedCalibration run_simulated_calibration(const RobotModel& nominal, const RobotModel& truth,
                                               const SimulatedProcedureOptions& options) {
  return run_simulated_calibration(nominal, truth, options, calibration_options_for(nominal));
}

SimulatedCalibration run_simulated_calibration(const RobotModel& nominal, const RobotModel& truth,
                                               const SimulatedProcedureOptions& options,
                                               const CalibrationOptions& calibration) {
  SimulatedCalibration out;
  std::uint64_t pass_seed = options.sim.seed;
  // One pass commanded with `commanding`; fresh noise per pass.
  const auto pass = [&](const RobotModel& commanding) -> const CalibrationResult& {
    SimulatedProcedureOptions pass_options = options;
    pass_options.sim.seed = pass_seed;
    pass_seed += 1000;
    out.logs = simulate_calibration_runs(commanding, truth, pass_options);
    std::vector<LockSpec> locks;
    for (const RunLog& log : out.logs) locks.push_back(*lock_from_comments(log));
    out.input = calibration_input_from_logs(out.logs, locks);
    out.result = calibrate(out.input, calibration);
    out.pass_results.push_back(out.result);
    return out.result;
  };
  if (!pass(nominal).ok() || !options.consistent_wheel_rates) return out;

  // The geometry of the first pass is free of the slip bias; only the radii are searched.
  // Residual: every single r estimate (2(N-1) per module) minus its module's commanded
  // radius. All vanish together only where the commanded rates agree; the mean alone would
  // leave a direction unobserved (slip that cancels over a module's runs).
  const std::size_t n = nominal.modules.size();
  RobotModel commanding = calibrated_model(nominal, out.result);
  const auto commanded = [&](const RobotModel& model) {
    Eigen::VectorXd v(static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; ++i) v(static_cast<Eigen::Index>(i)) = model.modules[i].wheel_radius_m;
    return v;
  };
  const auto residual = [&](const CalibrationResult& r, const Eigen::VectorXd& cmd) {
    std::vector<double> e;
    for (std::size_t i = 0; i < n; ++i) {
      for (double v : r.modules[i].wheel_radius_estimates_m) e.push_back(v - cmd(static_cast<Eigen::Index>(i)));
    }
    return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(e.data(), static_cast<Eigen::Index>(e.size())));
  };
  const auto set_radii = [&](RobotModel& model, const Eigen::VectorXd& v) {
    for (std::size_t i = 0; i < n; ++i) model.modules[i].wheel_radius_m = v(static_cast<Eigen::Index>(i));
  };
  const Eigen::VectorXd r0 = commanded(commanding);
  if (!pass(commanding).ok()) return out;
  const Eigen::VectorXd g0 = residual(out.result, r0);
  Eigen::MatrixXd jacobian(g0.size(), static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::VectorXd ri = r0;
    const auto col = static_cast<Eigen::Index>(i);
    const double h = options.radius_step * r0(col);
    ri(col) += h;
    set_radii(commanding, ri);
    if (!pass(commanding).ok()) return out;
    jacobian.col(col) = (residual(out.result, ri) - g0) / h;
  }
  // Gauss-Newton chord steps (the Jacobian hardly changes near the solution); the last pass
  // is the reported one, and its radii are estimated, not copied from the step.
  // Truncated: the unobservable pattern (see the header) has a near-zero singular value, and
  // stepping along it would only amplify noise.
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(jacobian, Eigen::ComputeThinU | Eigen::ComputeThinV);
  svd.setThreshold(0.05);
  Eigen::VectorXd r = r0;
  Eigen::VectorXd g = g0;
  for (int step = 0; step < options.newton_steps; ++step) {
    r -= svd.solve(g);
    set_radii(commanding, r);
    if (!pass(commanding).ok()) return out;
    g = residual(out.result, r);
  }
  return out;
}

}  // namespace swivel::calibration
