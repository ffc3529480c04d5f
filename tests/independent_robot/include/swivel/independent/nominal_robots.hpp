// SPDX-License-Identifier: Apache-2.0
#pragma once
// The two robots as their nominal model files describe them: what the controller knows and
// what the true robot is before any effect is applied.

#include <array>

#include "swivel/independent/differential_kinematics.hpp"
#include "swivel/independent/swpc_kinematics.hpp"

namespace swivel::independent {

inline constexpr int kEncoderCountsPerRev = 4096;  ///< wheel and steering encoders
inline constexpr double kGyroNoiseRadS = 0.002;
inline constexpr double kMocapPositionNoiseM = 0.0003;
inline constexpr double kMocapYawNoiseRad = 0.001;
inline constexpr double kMocapRateHz = 100.0;
inline constexpr double kLinearAccelLimitMps2 = 0.6;  ///< per axis (x, y)
inline constexpr double kAngularAccelLimitRadps2 = 2.0;
inline constexpr double kSteeringRateLimitRadps = 6.0;  ///< swpc4, per module

/// docent: r = 0.075 m both wheels, b = 0.40 m.
DifferentialGeometry docent_nominal();

/// swpc4: docs/methods.md §1's design values, modules in the order (0.215, 0.125),
/// (0.215, -0.125), (-0.215, -0.125), (-0.215, 0.125) m; d = 0.020 m, r = 0.055 m, offset 0.
std::array<SwpcModule, 4> swpc4_nominal();

}  // namespace swivel::independent
