// SPDX-License-Identifier: Apache-2.0
#pragma once
// One closed-loop run of the Table 5 square (docs/methods.md §1) on the simulated world: the
// robot follows the square on its own odometry, computed with the model it is given
// (nominal or calibrated), while the world moves with the true model.

#include <cstdint>
#include <vector>

#include "swivel/robot_model.hpp"
#include "swivel/sim/world.hpp"
#include "swivel/types.hpp"

namespace swivel::lab {

struct SquareRunOptions {
  double side_m = 2.5;
  int laps = 2;
  bool counter_clockwise = true;
  double rate_hz = 100.0;
  double max_duration_s = 600.0;
  std::uint64_t seed = 1;
  /// Random errors outside the kinematic models, the same for every controller model.
  sim::NonSystematicErrors nonsystematic;
  bool sensor_noise = true;
  /// The world's integration step. Coarser steps are quicker but not free: at 5 ms the true
  /// model's noise-free end error grows from 0.014 m to 0.023 m.
  double substep_s = 0.001;
  /// Keep every n-th true pose for the plot; 0 keeps none.
  int trace_every = 10;
};

struct SquareRunResult {
  Pose2 true_end;
  Pose2 odometry_end;
  double position_error_m = 0.0;   ///< |true end - commanded end|
  double heading_error_rad = 0.0;  ///< |wrap(true end yaw - commanded end yaw)|
  double duration_s = 0.0;
  bool finished = false;     ///< the follower reached its last corner before max_duration_s
  std::vector<Pose2> trace;  ///< true poses
};

/// Drives `truth` around the square with odometry and inverse kinematics of `controller`.
/// @throws std::invalid_argument for incompatible models; std::runtime_error when the world
///   rejects a step.
SquareRunResult run_square(const RobotModel& truth, const RobotModel& controller,
                           const SquareRunOptions& options);

}  // namespace swivel::lab
