// SPDX-License-Identifier: Apache-2.0
#pragma once
// A planar estimate's 3x3 covariance over (x, y, yaw), or a twist's over (vx, vy, wz), as the
// row-major 6x6 over (x, y, z, roll, pitch, yaw) of a ROS 2 message.
//
// robot_localization replaces a measurement variance below 1e-9 with 1e-9 (and says so),
// because a zero variance makes its Kalman gain singular. Swivel therefore never publishes an
// exact zero on the diagonal:
//  - z, roll and pitch (and their rates) are constrained by the plane the robot drives on: they
//    get kConstrainedVariance;
//  - x, y and yaw (and their rates) get at least kMeasuredVarianceFloor: a value below it (the
//    start-up pose, which is exact by definition; a rate the drivetrain cannot have, such as
//    vy of a differential robot; the encoders' quantization alone) would claim more than
//    wheel slip and geometry errors allow;
//  - an estimate without a covariance is unknown: kUnknownVariance on x, y and yaw.
// Raising a diagonal keeps a covariance positive semi-definite; the off-diagonal terms stay.

#include <array>
#include <cstddef>
#include <span>

namespace swivel::dds {

/// z, roll, pitch and their rates: σ = 1 mm or 1 mrad (m², rad², (m/s)², (rad/s)²).
inline constexpr double kConstrainedVariance = 1e-6;
/// Smallest variance of x, y and yaw and of their rates: σ = 1 mm (/s) or 1 mrad (/s).
inline constexpr double kMeasuredVarianceFloor = 1e-6;
/// x, y and yaw of an estimate that carries no covariance: σ = 1000 m or rad.
inline constexpr double kUnknownVariance = 1e6;

/// Fills `ros` (a ROS 2 message's 6x6, row-major) from `planar` (row-major over x, y, yaw or
/// vx, vy, wz; null when there is none), with the floors above.
inline void to_ros_covariance(const std::array<double, 9>* planar,
                              std::span<double, 36> ros) noexcept {
  constexpr std::array<std::size_t, 3> kPlanarIndex{0, 1, 5};
  constexpr std::array<std::size_t, 3> kConstrainedIndex{2, 3, 4};
  for (double& v : ros) v = 0.0;
  for (std::size_t r = 0; r < 3; ++r) {
    for (std::size_t c = 0; c < 3; ++c) {
      ros[kPlanarIndex[r] * 6 + kPlanarIndex[c]] =
          planar != nullptr ? (*planar)[r * 3 + c] : (r == c ? kUnknownVariance : 0.0);
    }
    double& variance = ros[kPlanarIndex[r] * 7];
    // Also raises a NaN (which the loop never publishes) to the floor.
    if (!(variance >= kMeasuredVarianceFloor)) variance = kMeasuredVarianceFloor;
  }
  for (const std::size_t i : kConstrainedIndex) ros[i * 7] = kConstrainedVariance;
}

}  // namespace swivel::dds
