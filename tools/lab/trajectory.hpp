// SPDX-License-Identifier: Apache-2.0
#pragma once
// Commanded body twists of the standard test motions of `swivel-lab simulate`.

#include <optional>
#include <string>
#include <vector>

#include "swivel/types.hpp"

namespace swivel::lab {

enum class TrajectoryKind {
  kStraight,       ///< forward at constant speed
  kArc,            ///< forward while turning: a circle
  kSpin,           ///< turn in place
  kFigure8,        ///< a counter-clockwise then a clockwise circle, repeated
  kStopAndGo,      ///< forward in bursts with stops (accelerations for slip and lag)
  kSquare,         ///< 2.5 m square at 0.2 m/s with 90 deg turns in place (docs/methods.md §1)
  kStrafe,         ///< sideways (swpc)
  kSpinTranslate,  ///< constant world-frame velocity while spinning (swpc)
  kCalibration,    ///< the locked-module calibration motion (swpc; not a twist profile)
};

/// Names accepted on the command line, in TrajectoryKind order.
const std::vector<std::string>& trajectory_names();
std::optional<TrajectoryKind> parse_trajectory(const std::string& name);
/// Whether the motion needs an omnidirectional (swpc) robot.
bool needs_swpc(TrajectoryKind kind);

/// A twist profile. Profiles ramp up over the first kRampS and down over the last kRampS of
/// the run; stop-and-go and square instead ramp each of their segments.
class Trajectory {
 public:
  static constexpr double kRampS = 0.5;

  Trajectory(TrajectoryKind kind, double duration_s);

  /// Natural length of one pass of the profile, s (e.g. one square lap).
  static double default_duration_s(TrajectoryKind kind);

  /// Commanded twist (robot frame) at time t_s in [0, duration].
  [[nodiscard]] Twist2 at(double t_s) const;

 private:
  struct Segment {
    double duration_s = 0.0;
    Twist2 twist;
    bool ramp = false;  // ramp up and down inside the segment (stops between segments)
  };
  [[nodiscard]] double envelope(double t_s) const;
  [[nodiscard]] double envelope_integral(double t_s) const;

  TrajectoryKind kind_;
  double duration_s_;
  std::vector<Segment> segments_;
  double period_s_ = 0.0;
};

}  // namespace swivel::lab
