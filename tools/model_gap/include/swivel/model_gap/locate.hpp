// SPDX-License-Identifier: Apache-2.0
#pragma once
// Motion phases of a run from its commands (standing, straight, turning, accelerating), for
// the report: where the robot was doing what. Where and how a residual grows is found per
// window by the replays and the misfit tests.

#include <cstddef>
#include <vector>

namespace swivel::model_gap {

enum class PhaseKind { kStanding, kStraight, kTurning, kAccelerating };

/// "standing", "straight", "turning", "accelerating".
const char* phase_name(PhaseKind kind);

/// One stretch of the run with a single motion phase, [start_s, end_s).
struct PhaseSegment {
  PhaseKind kind = PhaseKind::kStanding;
  double start_s = 0.0;
  double end_s = 0.0;
  std::size_t first = 0;  ///< first sample index
  std::size_t last = 0;   ///< last sample index (inclusive)
};

/// Thresholds for the phase classification of the commanded body twist.
struct PhaseThresholds {
  double standing_speed_mps = 0.01;
  double standing_rate_radps = 0.02;
  double turning_rate_radps = 0.05;  ///< below this a moving robot goes straight
  double accel_mps2 = 0.05;          ///< |d speed/dt| at or above this is accelerating
  double angular_accel_radps2 = 0.15;
  double derivative_window_s = 0.4;  ///< command steps are spread over this window
};

/// Commanded body twist over time (the run's cmd_vx, cmd_vy, cmd_wz columns).
struct CommandSeries {
  std::vector<double> t_s;
  std::vector<double> vx_mps;
  std::vector<double> vy_mps;
  std::vector<double> wz_radps;
};

/// Per-sample phase of the commands; accelerating wins over turning and straight.
std::vector<PhaseKind> classify_phases(const CommandSeries& cmd, const PhaseThresholds& th = {});

/// Consecutive samples of equal phase merged into segments.
std::vector<PhaseSegment> phase_segments(const std::vector<PhaseKind>& phases,
                                         const std::vector<double>& t_s);

}  // namespace swivel::model_gap
