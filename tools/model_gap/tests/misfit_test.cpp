// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/misfit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <utility>

namespace swivel::model_gap {
namespace {

constexpr std::size_t kWindows = 120;

// Two position channels and a heading channel of pure noise (sigma 1), with the robot
// turning through every heading and its wheels through every angle.
MisfitInputs noise_only(unsigned seed, std::size_t windows = kWindows) {
  MisfitInputs in;
  in.channels = {{"dx", "m", Question::kSensorToPose, ChannelKind::kPosition, 0},
                 {"dy", "m", Question::kSensorToPose, ChannelKind::kPosition, 0},
                 {"dyaw", "rad", Question::kSensorToPose, ChannelKind::kHeading, 0}};
  in.windows = windows;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (std::size_t c = 0; c < 3; ++c) {
    for (std::size_t j = 0; j < windows; ++j) {
      in.residuals.push_back(gauss(rng));
      in.sigma.push_back(1.0);
      in.own_change.push_back(0.3 * std::sin(0.37 * static_cast<double>(j)) + (c == 0 ? 0.2 : 0.0));
    }
  }
  in.wheel_sin_change.assign(1, std::vector<double>(windows));
  in.wheel_cos_change.assign(1, std::vector<double>(windows));
  for (std::size_t j = 0; j < windows; ++j) {
    in.accel.push_back(j % 7 == 0 ? 0.5 : 0.0);
    in.start_yaw_rad.push_back(0.29 * static_cast<double>(j));
    const double pa = 5.1 * static_cast<double>(j);
    const double pb = pa + 5.1;
    in.wheel_sin_change[0][j] = std::sin(pb) - std::sin(pa);
    in.wheel_cos_change[0][j] = std::cos(pb) - std::cos(pa);
  }
  return in;
}

double z_of(const std::vector<MisfitTest>& tests, const std::string& test,
            const std::string& channel) {
  for (const auto& t : tests) {
    if (t.test == test && t.channel == channel) return t.z;
  }
  ADD_FAILURE() << "no test " << test << " on " << channel;
  return 0.0;
}

TEST(Misfit, NoiseAloneLeavesEveryTestQuiet) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const auto tests = misfit_tests(noise_only(seed));
    ASSERT_FALSE(tests.empty());
    EXPECT_LT(tests.front().z, 5.0)
        << "seed " << seed << ": " << tests.front().test << " on " << tests.front().channel;
  }
}

TEST(Misfit, ADriftFixedInTheWorldIsFound) {
  MisfitInputs in = noise_only(7);
  // The world frame moves 2 sigma per window along world x: in the robot frame at each
  // window's start that is R(-yaw) (2, 0).
  for (std::size_t j = 0; j < kWindows; ++j) {
    in.residuals[0 * kWindows + j] += 2.0 * std::cos(in.start_yaw_rad[j]);
    in.residuals[1 * kWindows + j] += -2.0 * std::sin(in.start_yaw_rad[j]);
  }
  const auto tests = misfit_tests(in);
  EXPECT_GT(z_of(tests, "world_drift", "dx"), 5.0);
  EXPECT_EQ(tests.front().test, "world_drift");
}

TEST(Misfit, APatternWithTheWheelsTurnIsFound) {
  MisfitInputs in = noise_only(8);
  for (std::size_t j = 0; j < kWindows; ++j) in.residuals[j] += 1.5 * in.wheel_sin_change[0][j];
  const auto tests = misfit_tests(in);
  EXPECT_GT(z_of(tests, "wheel_periodic", "dx"), 5.0);
}

TEST(Misfit, ATrendAndAJumpAreFound) {
  MisfitInputs in = noise_only(9);
  for (std::size_t j = 0; j < kWindows; ++j)
    in.residuals[2 * kWindows + j] += 1.0;  // a constant rate
  in.residuals[0 * kWindows + 40] += 25.0;  // one jump
  const auto tests = misfit_tests(in);
  EXPECT_GT(z_of(tests, "trend", "dyaw"), 5.0);
  EXPECT_GT(z_of(tests, "jumps", "dx"), 5.0);
  for (const auto& t : tests) {
    if (t.test == "trend" && t.channel == "dyaw") {
      EXPECT_EQ(t.label, "grows with time");
    }
    if (t.test == "jumps" && t.channel == "dx") {
      EXPECT_EQ(t.label, "1 isolated jump");
    }
  }
}

// A transient the replay places a little later than the run moves residual from one window
// into the next: the pair cancels and is not a jump. The same two values in windows apart
// (say, dropped encoder counts twice) are.
TEST(Misfit, ATransientSplitAcrossTwoWindowsIsNotAJump) {
  MisfitInputs split = noise_only(10);
  split.residuals[0 * kWindows + 30] += 14.0;
  split.residuals[0 * kWindows + 31] -= 14.0;
  EXPECT_LT(z_of(misfit_tests(split), "jumps", "dx"), 5.0);

  MisfitInputs apart = noise_only(10);
  apart.residuals[0 * kWindows + 30] += 14.0;
  apart.residuals[0 * kWindows + 50] -= 14.0;
  EXPECT_GT(z_of(misfit_tests(apart), "jumps", "dx"), 5.0);

  MisfitInputs same_sign = noise_only(10);
  same_sign.residuals[0 * kWindows + 30] += 14.0;
  same_sign.residuals[0 * kWindows + 31] += 14.0;
  EXPECT_GT(z_of(misfit_tests(same_sign), "jumps", "dx"), 5.0);
}

// A caster's transient often straddles a window of much steering, whose noise is larger, and
// a quiet one: the same rotation, placed a little apart in time, cancels in the channel's
// units, whitened one by one it would not (here 30 of 3 and -30 of 1: 10 and -30 sigmas).
// Their sum is what counts, over the two windows' noise together.
TEST(Misfit, ATransientSplitAcrossANoisyAndAQuietWindowIsNotAJump) {
  MisfitInputs split = noise_only(10);
  split.sigma[0 * kWindows + 30] = 3.0;
  split.residuals[0 * kWindows + 30] = 3.0 * split.residuals[0 * kWindows + 30] + 30.0;
  split.residuals[0 * kWindows + 31] -= 30.0;
  EXPECT_LT(z_of(misfit_tests(split), "jumps", "dx"), 5.0);

  MisfitInputs apart = split;
  std::swap(apart.residuals[0 * kWindows + 31], apart.residuals[0 * kWindows + 50]);
  EXPECT_GT(z_of(misfit_tests(apart), "jumps", "dx"), 5.0);
}

// The jumps test lists its jumps' windows (a pair that cancels as one span of two), for the
// question to compare them with the residual before.
TEST(Misfit, JumpsNameTheirWindows) {
  MisfitInputs in = noise_only(11);
  in.residuals[0 * kWindows + 20] += 14.0;
  in.residuals[0 * kWindows + 60] += 30.0;
  in.residuals[0 * kWindows + 61] -= 24.0;
  for (const MisfitTest& t : misfit_tests(in)) {
    if (t.test != "jumps") continue;
    if (t.channel != "dx") {
      EXPECT_TRUE(t.jumps.empty()) << t.channel;
      continue;
    }
    ASSERT_EQ(t.jumps.size(), 1U) << "the cancelling pair is not a jump";
    EXPECT_EQ(t.jumps[0].first, 20U);
    EXPECT_EQ(t.jumps[0].count, 1U);
  }
  in.residuals[0 * kWindows + 61] += 24.0 + 30.0;  // the pair now adds up
  for (const MisfitTest& t : misfit_tests(in)) {
    if (t.test != "jumps" || t.channel != "dx") continue;
    ASSERT_EQ(t.jumps.size(), 3U);
    EXPECT_EQ(t.jumps[1].first, 60U);
    EXPECT_EQ(t.jumps[2].first, 61U);
  }
}

// A caster's steering jumps say whether they came where the commands barely roll it (less
// than two caster offsets over the window at their slowest): there a servo holding the caster
// against its tyre can let go within one window (tools/lab/GAP.md, section 9).
TEST(Misfit, ASteeringJumpSaysWhetherItsCasterBarelyRolled) {
  MisfitInputs in = noise_only(12);
  in.channels[2] = {"steer_2", "rad", Question::kCommandToMotion, ChannelKind::kSteerAngle, 1};
  in.residuals[2 * kWindows + 30] += 30.0;
  in.residuals[2 * kWindows + 80] -= 30.0;
  // Module 1 rolls ten offsets a window, except at rest in window 30 and slowly in window 80.
  in.slowest_roll_offsets.assign(2, std::vector<double>(kWindows, 10.0));
  in.slowest_roll_offsets[1][30] = 0.0;
  in.slowest_roll_offsets[1][80] = 1.5;
  const auto label = [&in] {
    for (const MisfitTest& t : misfit_tests(in)) {
      if (t.test == "jumps" && t.channel == "steer_2") return t.label;
    }
    return std::string("no test");
  };
  EXPECT_EQ(label(), "2 isolated jumps, all where its caster barely rolls");
  in.slowest_roll_offsets[1][80] = 2.5;
  EXPECT_EQ(label(), "2 isolated jumps, 1 where its caster barely rolls");
  in.slowest_roll_offsets[1][30] = 4.0;
  EXPECT_EQ(label(), "2 isolated jumps");
  // Another module's rest says nothing of this caster, nor a position channel's jumps.
  in.slowest_roll_offsets[0][30] = 0.0;
  EXPECT_EQ(label(), "2 isolated jumps");
  in.residuals[0 * kWindows + 30] += 30.0;
  for (const MisfitTest& t : misfit_tests(in)) {
    if (t.test == "jumps" && t.channel == "dx") {
      EXPECT_EQ(t.label, "1 isolated jump");
    }
  }
}

// A short run (30 windows, as a recording of half a minute gives) has few windows to
// estimate each pattern's uncertainty from, fewer still for a regressor that lives in a few
// windows (acceleration at the command steps). Its tests must still exceed 3 sigma on noise
// no more often than a normal deviate does (0.27 %), and 5 sigma, the bar, practically never.
TEST(Misfit, OnAShortRunNoiseExceedsThreeSigmaNoMoreOftenThanStated) {
  constexpr std::size_t kShort = 30;
  constexpr unsigned kRuns = 2000;
  std::size_t tests = 0;
  std::size_t over3 = 0;
  std::size_t over5 = 0;
  for (unsigned seed = 1; seed <= kRuns; ++seed) {
    for (const MisfitTest& t : misfit_tests(noise_only(seed, kShort))) {
      if (t.test == "jumps") continue;  // a count of windows, on its own scale
      ++tests;
      if (t.z > 3.0) ++over3;
      if (t.z > 5.0) ++over5;
    }
  }
  ASSERT_EQ(tests, 7U * kRuns);
  EXPECT_LT(static_cast<double>(over3) / static_cast<double>(tests), 2.0 * 0.0027)
      << over3 << " of " << tests << " above 3 sigma";
  EXPECT_EQ(over5, 0U) << "of " << tests;
}

// What the small-sample reference takes from noise it must not take from a clear pattern: a
// wheel pattern of 2.4 noise sigmas RMS on the same 30 windows is still found. (Thirty windows
// cannot make any pattern much more certain than 7 sigma: the noise is estimated from them.)
TEST(Misfit, APatternWithTheWheelsTurnIsFoundOnAShortRun) {
  constexpr std::size_t kShort = 30;
  std::size_t found = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    MisfitInputs in = noise_only(seed, kShort);
    for (std::size_t j = 0; j < kShort; ++j) in.residuals[j] += 3.0 * in.wheel_sin_change[0][j];
    if (z_of(misfit_tests(in), "wheel_periodic", "dx") > 5.0) ++found;
  }
  EXPECT_EQ(found, 20U);
}

}  // namespace
}  // namespace swivel::model_gap
