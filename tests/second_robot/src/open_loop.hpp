// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulation with the user's commands given rather than the path controller's: two
// robots on the same commands show what their difference does to the motion, which the path
// controller would otherwise steer back out of it.

#include <vector>

#include "swivel/second/second_robot.hpp"

namespace swivel::second {

/// simulate(spec), with the body-twist command of each planner period (vx, vy, wz per
/// Planner::kPeriodS) taken from `commands` where given (past its end, the path controller's),
/// and the commands used written to `used` where given.
std::vector<Row> simulate_commanded(const RunSpec& spec, const std::vector<double>* commands,
                                    std::vector<double>* used);

}  // namespace swivel::second
