// SPDX-License-Identifier: Apache-2.0
// The planar covariances as ROS 2 6x6 matrices: never an exact zero on the diagonal, which
// robot_localization would clamp (and warn about).

#include "swivel/dds/ros_covariance.hpp"

#include <gtest/gtest.h>

#include <array>

namespace swivel::dds {
namespace {

double diagonal(const std::array<double, 36>& m, std::size_t i) { return m[i * 7]; }

TEST(RosCovariance, PlanarEntriesLandOnXYAndYaw) {
  const std::array<double, 9> planar{0.1, 0.2, 0.3, 0.2, 0.5, 0.6, 0.3, 0.6, 0.9};
  std::array<double, 36> ros{};
  to_ros_covariance(&planar, ros);
  EXPECT_DOUBLE_EQ(ros[0], 0.1);
  EXPECT_DOUBLE_EQ(ros[1], 0.2);
  EXPECT_DOUBLE_EQ(ros[5], 0.3);
  EXPECT_DOUBLE_EQ(ros[6], 0.2);
  EXPECT_DOUBLE_EQ(ros[7], 0.5);
  EXPECT_DOUBLE_EQ(ros[11], 0.6);
  EXPECT_DOUBLE_EQ(ros[30], 0.3);
  EXPECT_DOUBLE_EQ(ros[31], 0.6);
  EXPECT_DOUBLE_EQ(ros[35], 0.9);
  EXPECT_DOUBLE_EQ(ros[2], 0.0);  // nothing couples x to z
}

TEST(RosCovariance, ExactZerosGetTheDocumentedFloors) {
  // The start-up pose of a filter, or vy of a differential robot: exact zeros.
  const std::array<double, 9> zero{};
  std::array<double, 36> ros{};
  ros.fill(7.0);  // whatever was there before is overwritten
  to_ros_covariance(&zero, ros);
  for (const std::size_t i : {0, 1, 5}) EXPECT_DOUBLE_EQ(diagonal(ros, i), kMeasuredVarianceFloor);
  for (const std::size_t i : {2, 3, 4}) EXPECT_DOUBLE_EQ(diagonal(ros, i), kConstrainedVariance);
  for (std::size_t r = 0; r < 6; ++r) {
    for (std::size_t c = 0; c < 6; ++c) {
      if (r != c) {
        EXPECT_EQ(ros[r * 6 + c], 0.0) << r << "," << c;
      }
    }
  }
  // Both floors are above robot_localization's clamp.
  EXPECT_GT(kMeasuredVarianceFloor, 1e-9);
  EXPECT_GT(kConstrainedVariance, 1e-9);
}

TEST(RosCovariance, VariancesAboveTheFloorAreKept) {
  const std::array<double, 9> planar{4e-6, 0.0, 0.0, 0.0, 2e-7, 0.0, 0.0, 0.0, 3e-2};
  std::array<double, 36> ros{};
  to_ros_covariance(&planar, ros);
  EXPECT_DOUBLE_EQ(diagonal(ros, 0), 4e-6);
  EXPECT_DOUBLE_EQ(diagonal(ros, 1), kMeasuredVarianceFloor);  // raised
  EXPECT_DOUBLE_EQ(diagonal(ros, 5), 3e-2);
}

TEST(RosCovariance, NoCovarianceIsUnknownNotCertain) {
  std::array<double, 36> ros{};
  to_ros_covariance(nullptr, ros);
  for (const std::size_t i : {0, 1, 5}) EXPECT_DOUBLE_EQ(diagonal(ros, i), kUnknownVariance);
  for (const std::size_t i : {2, 3, 4}) EXPECT_DOUBLE_EQ(diagonal(ros, i), kConstrainedVariance);
}

}  // namespace
}  // namespace swivel::dds
