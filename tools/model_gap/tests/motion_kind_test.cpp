// SPDX-License-Identifier: Apache-2.0
// Which runs drive one circle (wheel radii then trade against the tracked body's lever arm).

#include "motion_kind.hpp"

#include <gtest/gtest.h>

#include <cstddef>
#include <utility>
#include <vector>

namespace swivel::model_gap {
namespace {

using Seconds = std::vector<std::pair<double, double>>;  // (left, right) wheel travel, rad

Seconds repeat(std::pair<double, double> step, std::size_t n) {
  Seconds s;
  s.assign(n, step);
  return s;
}

TEST(MotionKind, ACircleDrivenOneWayIsOneCircle) {
  EXPECT_TRUE(drives_one_circle(repeat({2.0, 3.0}, 20)));
  // Backwards round the same circle bends the same way.
  Seconds both = repeat({2.0, 3.0}, 10);
  for (const auto& s : repeat({-2.0, -3.0}, 10)) both.push_back(s);
  EXPECT_TRUE(drives_one_circle(both));
}

TEST(MotionKind, StraightDrivingIsNoCircle) {
  EXPECT_FALSE(drives_one_circle(repeat({3.0, 3.0}, 20)));
  EXPECT_FALSE(drives_one_circle({}));
}

TEST(MotionKind, ArcsThatBendBothWaysAreNoCircle) {
  Seconds s = repeat({2.0, 3.0}, 10);
  for (const auto& step : repeat({3.0, 2.0}, 10)) s.push_back(step);
  EXPECT_FALSE(drives_one_circle(s));
}

// A recorded drive of the simulated docent under acceleration limits (swiveld_model_loop_test's
// script: straight, arcs left and right at several speeds, a spin): the spin shares of its
// seconds spread by just under 0.3, as one circle's would, but its arcs bend both ways.
TEST(MotionKind, AFigureWithArcsBothWaysUnderLimitsIsNoCircle) {
  const Seconds drive = {{0.028, 0.028}, {3.346, 3.346}, {3.309, 4.692}, {2.410, 5.587},
                         {2.885, 1.287}, {1.450, 0.686}, {0.104, 2.477}, {4.056, 2.517},
                         {0.387, 0.377}, {0.058, 0.058}, {3.464, 3.464}, {3.251, 4.749},
                         {2.399, 5.533}, {2.930, 1.173}, {1.262, 0.716}, {-0.080, 2.266}};
  EXPECT_FALSE(drives_one_circle(drive));
}

}  // namespace
}  // namespace swivel::model_gap
