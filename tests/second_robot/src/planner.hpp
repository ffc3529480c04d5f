// SPDX-License-Identifier: Apache-2.0
#pragma once
// The user's side: a drive script of segments (go to a waypoint, drive a circle, turn on the
// spot, pause) followed by a path controller that turns the robot's pose into a body-twist
// command at its own rate (25 Hz). The command is what the run log's cmd_* columns carry.

#include <cstdint>
#include <vector>

#include "swivel/second/second_robot.hpp"

namespace swivel::second {

struct Segment {
  enum class Kind { kPause, kGoto, kCircle, kCrabCircle, kSpotTurn } kind = Kind::kPause;
  double duration_s = 0.0;  ///< pause
  double x_m = 0.0;         ///< goto target, world
  double y_m = 0.0;
  double yaw_rad = 0.0;    ///< goto: target yaw (swpc)
  double radius_m = 0.0;   ///< circles
  double angle_rad = 0.0;  ///< circles and turns: signed angle to travel
  double speed = 0.0;      ///< m/s (circles) or rad/s (turns)
};

class Planner {
 public:
  static constexpr double kPeriodS = 0.04;
  static constexpr double kEaseLinearMps2 = 0.15;  ///< the user's own ramp of each axis
  static constexpr double kEaseAngularRadps2 = 0.4;
  static constexpr double kCasterEaseShare = 0.6;

  Planner(const Design& design, Script script, std::uint64_t seed, const double start_pose[3],
          double duration_s);

  /// The command for the next period from the current pose (world) at time t.
  void update(double t_s, const double pose[3]);
  [[nodiscard]] const double* command() const { return cmd_; }
  [[nodiscard]] const std::vector<Segment>& segments() const { return segments_; }

 private:
  void target(double t_s, const double pose[3]);  ///< the command before easing
  void next_segment(double t_s);
  void goto_command(const Segment& s, const double pose[3]);

  Design design_;
  double duration_s_;
  std::vector<Segment> segments_;
  std::size_t current_ = 0;
  double segment_start_s_ = 0.0;
  double cmd_[3] = {0, 0, 0};
  double eased_[3] = {0, 0, 0};
};

}  // namespace swivel::second
