// SPDX-License-Identifier: Apache-2.0
#pragma once
// The noise of each channel's window residuals, estimated from the run itself: a variance
// a + b x per window, where x is the square of how far the wheels (or the steering) turned
// in the window. `a` holds what every window has (motion-capture noise at its ends, gyro
// noise, encoder quantization), `b` what grows with the motion (random wheel slip, the
// heading noise of the window's start turning its displacement). Robust to a few outlying
// windows.

#include <cstddef>
#include <vector>

namespace swivel::model_gap {

struct NoiseModel {
  std::vector<double> a;  ///< per channel, squared channel units
  std::vector<double> b;  ///< per channel, squared channel units per unit of x

  /// Standard deviation of channel c's residual in a window with regressor x and a known
  /// variance `known` of its own (see estimate_noise).
  [[nodiscard]] double sigma(std::size_t c, double x, double known = 0.0) const;
};

/// Fits a + b x to the squared residuals of every channel (channel-major `residuals`,
/// `windows` per channel; x[c][w]), with a at least floor_variance[c] and b >= 0, on top of a
/// variance already known per window (`known`, channel-major, or empty: none), such as what
/// a replay's own uncertainty adds. Windows whose squared residual exceeds 16 times the
/// model are left out as outliers.
NoiseModel estimate_noise(const std::vector<double>& residuals, std::size_t windows,
                          const std::vector<std::vector<double>>& x,
                          const std::vector<double>& floor_variance,
                          const std::vector<double>& known = {});

}  // namespace swivel::model_gap
