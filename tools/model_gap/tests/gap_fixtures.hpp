// SPDX-License-Identifier: Apache-2.0
#pragma once
// Measured-style runs for the model-gap tests and benchmark: a robot whose true model
// carries hidden effects, driven by a controller that uses the nominal model, recorded with
// the simulator's sensor noise and encoder quantization.

#include <cstdint>
#include <string>
#include <vector>

#include "swivel/robot_model.hpp"
#include "swivel/run_log.hpp"

namespace swivel::model_gap::testing {

/// config/robots/<name>.yaml of the source tree.
RobotModel robot(const std::string& name);

/// Commanded twist at time t of a repeating 20 s pattern: standing, ramps, straight runs,
/// arcs, turns in place (and sideways and diagonal motion for a holonomic robot).
Twist2 pattern_command(double t_s, bool holonomic);

/// Simulates `duration_s` of the pattern at `rate_hz` with the world using `truth` and the
/// controller using `nominal`. The world is read once a row, so its gyro column is the mean
/// rate over the row (declared: RunLogHeader::gyro_mean_over_row).
RunLog simulate_run(const RobotModel& nominal, const RobotModel& truth, double duration_s,
                    std::uint64_t seed, double rate_hz = 100.0);

/// One step of a motion script (swiveld's `command.script`): a twist held for duration_s.
struct ScriptStep {
  Twist2 twist;
  double duration_s = 0.0;
};

/// Records `duration_s` of `script` (played in a loop) the way swiveld records the simulated
/// robot: a 1 kHz loop reads the world every cycle and drives it with the nominal model's
/// inverse kinematics (through a limiter with the nominal model's `limits:`), and each row
/// at `rate_hz` takes the latest cycle's readings and command. So gyro_wz is the reading at
/// the row's time (the world's mean over the last 1 ms cycle), as swivel/run_log.hpp
/// defines it, with no declaration. The script is at `script_phase_s` into its loop at the
/// first row: the daemon plays it from its start, the recording starts when it is asked to,
/// so a step of the script falls anywhere within a row.
RunLog record_like_swiveld(const RobotModel& nominal, const RobotModel& truth,
                           const std::vector<ScriptStep>& script, double duration_s,
                           std::uint64_t seed, double script_phase_s = 0.0, double rate_hz = 100.0);

/// Rewrites the left (first) wheel's encoder as if its effective radius varied with its
/// angle, r (1 + amplitude cos psi): an effect outside the library.
void add_eccentric_wheel(RunLog& log, double amplitude);

}  // namespace swivel::model_gap::testing
