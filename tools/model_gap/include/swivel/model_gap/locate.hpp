#pragma once
// Locating a model gap: motion phases from the commands, time windows where a residual
// grows, and the character of the growth (constant, with time, distance, rotation,
// acceleration, or lagging) by regressing the residual on those signals.

#include <string>
#include <vector>

#include "swivel/model_gap/channels.hpp"

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
  double turning_rate_radps = 0.05;       ///< below this a moving robot goes straight
  double accel_mps2 = 0.05;               ///< |d speed/dt| at or above this is accelerating
  double angular_accel_radps2 = 0.15;
  double derivative_window_s = 0.4;       ///< command steps are spread over this window
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

/// Signals derived from the commands that residuals are regressed on.
struct MotionSignals {
  std::vector<double> time_s;          ///< since the start
  std::vector<double> distance_m;      ///< integral of commanded speed
  std::vector<double> rotation_rad;    ///< integral of commanded yaw rate (signed)
  std::vector<double> speed_mps;
  std::vector<double> yaw_rate_radps;
  std::vector<double> accel_mps2;      ///< signed, smoothed
  std::vector<double> velocity_change_mps;  ///< integral of |accel| (cumulative)
};

MotionSignals motion_signals(const CommandSeries& cmd, const PhaseThresholds& th = {});

/// How a residual grows, as found by single-signal regressions.
struct Character {
  std::string label;      ///< "constant offset", "grows with distance", ..., "irregular"
  std::string signal;     ///< regressor that explains it best, "" for irregular
  double r_squared = 0.0; ///< fraction of the residual's variance it explains
  double slope = 0.0;     ///< residual units per signal unit
};

/// Character of `residual` given the motion signals and the channel's prediction (used for
/// the lag regressor: a lag tau leaves a residual of about -tau * d(prediction)/dt).
/// Samples where the residual is NaN are skipped.
Character characterise(const std::vector<double>& residual, const std::vector<double>& predicted,
                       const ChannelInfo& info, const MotionSignals& signals);

/// A stretch of time during which a channel's residual magnitude grows quickly.
struct GrowthWindow {
  double start_s = 0.0;
  double end_s = 0.0;
  double growth = 0.0;  ///< increase of |residual| over the window, channel units
  PhaseKind dominant_phase = PhaseKind::kStanding;
};

/// Windows (1 s bins merged) where |residual| grows by more than `min_growth_per_s`
/// per second and by more than a fifth of the fastest bin; at most `max_windows`, largest
/// growth first.
std::vector<GrowthWindow> growth_windows(const std::vector<double>& residual,
                                         const std::vector<double>& t_s,
                                         const std::vector<PhaseKind>& phases,
                                         double min_growth_per_s, std::size_t max_windows = 6);

/// Residual statistics of one channel within one phase kind.
struct PhaseStat {
  PhaseKind kind = PhaseKind::kStanding;
  double duration_s = 0.0;
  double rms = 0.0;              ///< RMS residual during the phase
  double growth_per_s = 0.0;     ///< mean |change of residual| per second during the phase
};

std::vector<PhaseStat> phase_stats(const std::vector<double>& residual,
                                   const std::vector<PhaseSegment>& segments);

}  // namespace swivel::model_gap
