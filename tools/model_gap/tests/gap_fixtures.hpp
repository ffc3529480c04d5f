// SPDX-License-Identifier: Apache-2.0
#pragma once
// Measured-style runs for the model-gap tests and benchmark: a robot whose true model
// carries hidden effects, driven by a controller that uses the nominal model, recorded with
// the simulator's sensor noise and encoder quantization.

#include <cstdint>
#include <string>

#include "swivel/robot_model.hpp"
#include "swivel/run_log.hpp"

namespace swivel::model_gap::testing {

/// config/robots/<name>.yaml of the source tree.
RobotModel robot(const std::string& name);

/// Commanded twist at time t of a repeating 20 s pattern: standing, ramps, straight runs,
/// arcs, turns in place (and sideways and diagonal motion for a holonomic robot).
Twist2 pattern_command(double t_s, bool holonomic);

/// Simulates `duration_s` of the pattern at `rate_hz` with the world using `truth` and the
/// controller using `nominal`.
RunLog simulate_run(const RobotModel& nominal, const RobotModel& truth, double duration_s,
                    std::uint64_t seed, double rate_hz = 100.0);

/// Rewrites the left (first) wheel's encoder as if its effective radius varied with its
/// angle, r (1 + amplitude cos psi): an effect outside the library.
void add_eccentric_wheel(RunLog& log, double amplitude);

}  // namespace swivel::model_gap::testing
