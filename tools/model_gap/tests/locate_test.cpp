// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/locate.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace swivel::model_gap {
namespace {

// 0-2 s standing, 2-3 s speeding up, 3-8 s straight at 0.4 m/s, 8-12 s turning.
CommandSeries drive_then_turn() {
  CommandSeries c;
  for (int k = 0; k <= 1200; ++k) {
    const double t = 0.01 * k;
    c.t_s.push_back(t);
    double v = 0.0;
    if (t >= 2.0 && t < 3.0) v = 0.4 * (t - 2.0);
    if (t >= 3.0 && t < 8.0) v = 0.4;
    c.vx_mps.push_back(v);
    c.vy_mps.push_back(0.0);
    c.wz_radps.push_back(t >= 8.0 ? 0.5 : 0.0);
  }
  return c;
}

TEST(LocateTest, ClassifiesStandingAcceleratingStraightTurning) {
  const auto cmd = drive_then_turn();
  const auto phases = classify_phases(cmd);
  EXPECT_EQ(phases[100], PhaseKind::kStanding);      // 1 s
  EXPECT_EQ(phases[250], PhaseKind::kAccelerating);  // 2.5 s
  EXPECT_EQ(phases[550], PhaseKind::kStraight);      // 5.5 s
  EXPECT_EQ(phases[1000], PhaseKind::kTurning);      // 10 s
  const auto segments = phase_segments(phases, cmd.t_s);
  ASSERT_GE(segments.size(), 4U);
  EXPECT_EQ(segments.front().kind, PhaseKind::kStanding);
  EXPECT_EQ(segments.back().kind, PhaseKind::kTurning);
  EXPECT_NEAR(segments.back().end_s, 12.0, 1e-9);
}

}  // namespace
}  // namespace swivel::model_gap
