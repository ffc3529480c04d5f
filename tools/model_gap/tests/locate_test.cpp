#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "swivel/model_gap/locate.hpp"

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
  EXPECT_EQ(phases[100], PhaseKind::kStanding);     // 1 s
  EXPECT_EQ(phases[250], PhaseKind::kAccelerating); // 2.5 s
  EXPECT_EQ(phases[550], PhaseKind::kStraight);     // 5.5 s
  EXPECT_EQ(phases[1000], PhaseKind::kTurning);     // 10 s
  const auto segments = phase_segments(phases, cmd.t_s);
  ASSERT_GE(segments.size(), 4U);
  EXPECT_EQ(segments.front().kind, PhaseKind::kStanding);
  EXPECT_EQ(segments.back().kind, PhaseKind::kTurning);
  EXPECT_NEAR(segments.back().end_s, 12.0, 1e-9);
}

TEST(LocateTest, SignalsIntegrateDistanceAndRotation) {
  const auto s = motion_signals(drive_then_turn());
  EXPECT_NEAR(s.distance_m.back(), 0.2 + 0.4 * 5.0, 0.01);
  EXPECT_NEAR(s.rotation_rad.back(), 0.5 * 4.0, 0.01);
}

TEST(LocateTest, CharacterisesResidualByItsCause) {
  const auto cmd = drive_then_turn();
  const auto s = motion_signals(cmd);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-4);
  const std::size_t n = cmd.t_s.size();
  std::vector<double> with_rotation(n);
  std::vector<double> with_distance(n);
  std::vector<double> constant(n);
  std::vector<double> with_time(n);
  std::vector<double> lagging(n);
  std::vector<double> predicted(n);
  for (std::size_t k = 0; k < n; ++k) {
    with_rotation[k] = 0.02 * s.rotation_rad[k] + noise(rng);
    with_distance[k] = 0.01 * s.distance_m[k] + noise(rng);
    constant[k] = 0.003 + noise(rng);
    with_time[k] = 0.001 * s.time_s[k] + noise(rng);
    predicted[k] = std::sin(s.time_s[k]);
    lagging[k] = -0.05 * std::cos(s.time_s[k]) + noise(rng);  // 50 ms lag of sin(t)
  }
  const ChannelInfo heading{"yaw", "rad", Question::kSensorToPose, ChannelKind::kHeading};
  const auto rot = characterise(with_rotation, predicted, heading, s);
  EXPECT_EQ(rot.label, "grows with rotation");
  EXPECT_NEAR(rot.slope, 0.02, 1e-3);
  EXPECT_EQ(characterise(with_distance, predicted, heading, s).label, "grows with distance");
  EXPECT_EQ(characterise(constant, predicted, heading, s).label, "constant offset");
  EXPECT_EQ(characterise(with_time, predicted, heading, s).label, "grows with time");
  const auto lag = characterise(lagging, predicted, heading, s);
  EXPECT_EQ(lag.label, "lagging");
  EXPECT_NEAR(lag.slope, 0.05, 0.005);
}

TEST(LocateTest, PureNoiseIsIrregular) {
  const auto cmd = drive_then_turn();
  const auto s = motion_signals(cmd);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> r(cmd.t_s.size());
  for (auto& v : r) v = noise(rng);
  const ChannelInfo gyro{"gyro", "rad/s", Question::kCommandToSensor, ChannelKind::kYawRate};
  EXPECT_EQ(characterise(r, std::vector<double>(r.size(), 0.0), gyro, s).label, "irregular");
}

TEST(LocateTest, GrowthWindowFindsTheTurn) {
  const auto cmd = drive_then_turn();
  const auto s = motion_signals(cmd);
  const auto phases = classify_phases(cmd);
  std::vector<double> r(cmd.t_s.size());
  for (std::size_t k = 0; k < r.size(); ++k) r[k] = 0.05 * s.rotation_rad[k];
  const auto windows = growth_windows(r, cmd.t_s, phases, 1e-3);
  ASSERT_FALSE(windows.empty());
  EXPECT_NEAR(windows[0].start_s, 8.0, 1.01);
  EXPECT_NEAR(windows[0].end_s, 12.0, 1e-9);
  EXPECT_EQ(windows[0].dominant_phase, PhaseKind::kTurning);
  const auto stats = phase_stats(r, phase_segments(phases, cmd.t_s));
  for (const auto& st : stats) {
    if (st.kind == PhaseKind::kTurning) {
      EXPECT_NEAR(st.growth_per_s, 0.025, 0.003);
    }
    if (st.kind == PhaseKind::kStraight) {
      EXPECT_NEAR(st.growth_per_s, 0.0, 1e-9);
    }
  }
}

}  // namespace
}  // namespace swivel::model_gap
