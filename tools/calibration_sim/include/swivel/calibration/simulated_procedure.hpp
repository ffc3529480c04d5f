// SPDX-License-Identifier: Apache-2.0
#pragma once
// The calibration of docs/methods.md §1 on the simulated world, offline: the daemon's procedure
// (calibration_procedure.hpp, the state machine its `swpc_geometric` plugin runs) stepped
// at the loop rate against a sim::World whose robot has the TRUE model, read -> procedure
// -> write as the daemon's loop does it, then the same analysis. What the world adds:
// quantized encoders, motion-capture noise, the true geometry and, when asked for,
// non-systematic errors. Not real-time safe.

#include <cstdint>
#include <string>

#include "swivel/calibration/calibration_procedure.hpp"
#include "swivel/calibration/swpc_calibration.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/sim/world.hpp"

namespace swivel::calibration {

struct SimulatedProcedureOptions {
  /// The procedure, as the plugin's parameters set it (defaults: the daemon's).
  ProcedureOptions procedure;
  /// The loop rate: one procedure step and one world step per cycle (the daemon: 1 kHz).
  double loop_rate_hz = 1000.0;
  /// Noise, quantization, non-systematic errors and seed of the world. The casters start
  /// where initial_steer_rad says; the procedure aligns them before each run.
  sim::SimOptions sim;
  /// Steering encoders that report angles wrapped to (c - pi, c + pi] around c =
  /// steering_wrap_center_rad, as absolute encoders do around their mounting.
  bool wrap_steering = false;
  double steering_wrap_center_rad = 0.0;
  /// While the procedure records: steering readings that flicker by this much, up or down
  /// from cycle to cycle in an irregular pattern, as a real encoder's do at a count boundary,
  /// rad (the world's readings do not).
  double steering_flicker_rad = 0.0;
};

struct SimulatedCalibration {
  CalibrationInput input;    ///< the recorded runs (module-major, then angle)
  CalibrationResult result;  ///< the analysis of them
  double duration_s = 0.0;   ///< simulated time the procedure took
};

/// Runs the procedure on a world with model `truth`, commanded with `nominal`, and
/// analyses it as the daemon does.
/// @throws ProcedureConfigError when the procedure cannot be planned (e.g. a free caster
///   within its caster offset of a pivot); std::invalid_argument for incompatible models;
///   std::runtime_error naming the reason when the procedure or the world fails on the way.
SimulatedCalibration run_simulated_calibration(const RobotModel& nominal, const RobotModel& truth,
                                               const SimulatedProcedureOptions& options);

}  // namespace swivel::calibration
