// SPDX-License-Identifier: Apache-2.0
#pragma once
// A waypoint follower for the square path of docs/methods.md §1 (Table 5): straight legs between
// corners and turns in place at them, closed on the robot's own odometry pose. It returns
// body twists; the caller turns them into actuator setpoints with its model's inverse
// kinematics, so a wrong model shows up as the true path drifting from the commanded one.

#include <cstddef>
#include <vector>

#include "swivel/types.hpp"

namespace swivel::lab {

struct SquareFollowerLimits {
  double speed_mps = 0.2;
  double yaw_rate_radps = 0.3;
  double accel_mps2 = 0.2;
  double yaw_accel_radps2 = 0.6;
  double cross_track_gain_per_s = 1.0;  ///< lateral correction per metre off the line
  double heading_gain_per_s = 2.0;
  double position_tolerance_m = 0.001;
  double heading_tolerance_rad = 0.0005;
};

class SquareFollower {
 public:
  /// A square of side `side_m` from `start` (a corner, heading along the first side),
  /// `laps` times, counter-clockwise (turns +90 deg) or clockwise, with a turn at every
  /// corner including the last, so that the commanded end pose is the start pose.
  SquareFollower(const Pose2& start, double side_m, int laps, bool counter_clockwise,
                 const SquareFollowerLimits& limits = {});

  /// Body twist to command for odometry pose `odom` over the next `dt_s`.
  Twist2 update(const Pose2& odom, double dt_s);
  [[nodiscard]] bool done() const { return leg_ >= legs_.size(); }
  /// The commanded corners in order, start included (world = odometry frame at t = 0).
  [[nodiscard]] const std::vector<Pose2>& corners() const { return corners_; }

 private:
  struct Leg {
    bool turn = false;
    Pose2 from;
    Pose2 to;  ///< for a turn only yaw_rad matters
  };
  Twist2 limit(const Twist2& wanted, double dt_s);

  SquareFollowerLimits limits_;
  std::vector<Leg> legs_;
  std::vector<Pose2> corners_;
  std::size_t leg_ = 0;
  Twist2 last_;  // body twist commanded last, for the acceleration limits
};

}  // namespace swivel::lab
