#pragma once
// The whole calibration procedure of PAPERS.md §1 on the simulated world: for each module
// in turn, lock it at each of the locked angles, drive the others with constant wheel rates
// (chosen with the NOMINAL model) and free steering, record motion capture and encoders as
// run logs, and calibrate from them. Unlike generate_calibration_motion (exact geometry),
// the motion here comes from the simulator: the true model, quantized encoders, sensor
// noise and non-systematic errors. Not real-time safe.
//
// The simulated wheels are velocity-controlled, while the paper drives them with constant
// torque so that each rolls at whatever rate the rotation asks of it. Rates chosen with a
// wrong model ask the free wheels for mutually inconsistent arcs: they slip against one
// another and the wheel radii come out biased by about the model's own error (1 % for the
// paper's robot). To stand in for the torque drive, the procedure searches for the wheel
// radii under which the commanded rates are consistent (the calibration then returns the
// radii it was commanded with): chord-Newton steps on that fixed point, the Jacobian from
// one extra pass per module with that module's commanded radius perturbed. With the
// paper's rectangular layout one pattern (+, -, +, - around the robot) stays unobservable:
// for a locked corner the diagonal wheel's lever arm squared equals the sum of the adjacent
// ones', so that pattern's slip leaves every r estimate consistent. The search leaves it
// as the first pass found it.

#include <cstdint>
#include <vector>

#include "swivel/calibration/swpc_calibration.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/run_log.hpp"
#include "swivel/sim/world.hpp"

namespace swivel::calibration {

struct SimulatedProcedureOptions {
  /// Measured steering angles at which each module is locked (the paper: 45 and 165 deg).
  std::vector<double> locked_angles_meas_rad = {0.7853981633974483, 2.8797932657906435};
  /// Commanded rotation per run; positive = counter-clockwise.
  double rotation_rad = 1.5707963267948966;
  double yaw_rate_radps = 0.3;  ///< magnitude of the commanded yaw rate
  double rate_hz = 100.0;       ///< control and logging rate
  /// Search for consistent wheel rates (see above); false: one pass commanded with the
  /// nominal model, whose radii then carry the slip bias.
  bool consistent_wheel_rates = true;
  /// Relative perturbation of a commanded radius for the Jacobian.
  double radius_step = 0.01;
  int newton_steps = 3;  ///< chord steps with that Jacobian, one pass each
  /// Noise, quantization, non-systematic errors and seed of the world; run j uses seed
  /// sim.seed + j so that the runs' noise is independent. initial_steer_rad is set per run
  /// (the free casters start aligned, as the paper aligns them before each run).
  sim::SimOptions sim;
};

struct SimulatedCalibration {
  std::vector<RunLog> logs;  ///< of the last pass, one per run: module-major, then angle
  CalibrationInput input;    ///< of the last pass
  CalibrationResult result;  ///< of the last pass (stops at the first refusal)
  std::vector<CalibrationResult> pass_results;  ///< every pass, in order
  std::size_t passes() const { return pass_results.size(); }
};

/// Simulates the runs of the procedure on a world with model `truth`, commanded with
/// `nominal`, and writes each as a run log (with its `# calibration:` comment).
/// @throws std::invalid_argument when the models are not compatible swpc models, a free
///   caster cannot self-align about a pivot, or the world rejects a step.
std::vector<RunLog> simulate_calibration_runs(const RobotModel& nominal, const RobotModel& truth,
                                              const SimulatedProcedureOptions& options);

/// The procedure: passes of simulate_calibration_runs, calibration_input_from_logs and
/// calibrate() (with calibration_options_for(nominal) unless `calibration` is given), the
/// first commanded with `nominal`, the others as described above. Stops at a refusal.
SimulatedCalibration run_simulated_calibration(const RobotModel& nominal, const RobotModel& truth,
                                               const SimulatedProcedureOptions& options);
SimulatedCalibration run_simulated_calibration(const RobotModel& nominal, const RobotModel& truth,
                                               const SimulatedProcedureOptions& options,
                                               const CalibrationOptions& calibration);

}  // namespace swivel::calibration
