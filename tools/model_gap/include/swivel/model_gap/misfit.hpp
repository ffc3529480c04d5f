// SPDX-License-Identifier: Apache-2.0
#pragma once
// Tests for a residual that no library effect accounts for, run on what is left after the
// selected effects: a residual that still grows with time, with the motion or with the
// acceleration; a drift fixed in the world frame (the motion capture's frame creeping
// against the floor); a pattern that repeats with a wheel's turn (an eccentric or
// out-of-round wheel); isolated jumps (an encoder that dropped counts, a motion-capture
// glitch). Each test is a least-squares regression of the whitened window residuals with
// an autocorrelation-robust Wald statistic (fit.hpp); a library effect is named only when
// every test stays quiet.

#include <cstddef>
#include <string>
#include <vector>

#include "swivel/model_gap/channels.hpp"

namespace swivel::model_gap {

struct MisfitTest {
  std::string test;     ///< "trend", "world_drift", "wheel_periodic", "jumps"
  std::string channel;  ///< channel name (the first of a pair for world_drift)
  std::string label;    ///< readable, e.g. "grows with time", "repeats with wheel l's turn"
  double z = 0.0;       ///< significance as a normal deviate
  double share = 0.0;   ///< share of the channel's residual sum of squares it explains
  /// RMS of what it explains over the RMS of what remains around it (jumps: the largest
  /// over the channel's robust spread)
  double size = 0.0;
  std::size_t module = 0;
  /// jumps: the windows of each jump past the bar, [first, first + count) (count 2: a
  /// transient the run and the replay place in neighbouring windows).
  struct Span {
    std::size_t first = 0;
    std::size_t count = 1;
  };
  std::vector<Span> jumps;
  /// jumps: every one is what a selected effect left of a larger change it brought there
  /// (set by the question, which knows the residual before): the effect's form is approximate
  /// where it acts, not something else missing.
  bool remnant = false;
};

/// What every channel's residual looks like in a window, for the regressions.
struct MisfitInputs {
  std::vector<ChannelInfo> channels;
  std::size_t windows = 0;
  std::vector<double> residuals;  ///< channel-major, channel units (NaN: no data)
  std::vector<double> sigma;      ///< channel-major noise standard deviation per window
  /// Channel-major: the predicted change of each channel's own quantity in the window
  /// (displacement along the channel's axis, heading change, wheel or steering rotation).
  /// Predicted, not measured: a measured change shares its noise with the residual.
  std::vector<double> own_change;
  std::vector<double> accel;                          ///< per window: mean |commanded acceleration|
  std::vector<double> start_yaw_rad;                  ///< per window: world heading at its start
  std::vector<std::vector<double>> wheel_sin_change;  ///< [module][window]
  std::vector<std::vector<double>> wheel_cos_change;
  /// [module][window], casters only (else empty): how far the commands carry the module's
  /// steering axis over the window at their slowest there, in caster offsets. Below a few, the
  /// caster barely rolls, and a servo holding it against its tyre can give way in one window.
  std::vector<std::vector<double>> slowest_roll_offsets;
};

/// Every test on every channel it applies to, most significant first.
std::vector<MisfitTest> misfit_tests(const MisfitInputs& in);

}  // namespace swivel::model_gap
