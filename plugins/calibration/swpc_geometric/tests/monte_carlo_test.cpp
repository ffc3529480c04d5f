// SPDX-License-Identifier: Apache-2.0
#include "swivel/calibration/monte_carlo.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace swivel::calibration {
namespace {

TEST(MonteCarlo, ShortNoiseFreeRunRecoversToMachinePrecision) {
  MonteCarloOptions opt;
  opt.trials = 200;
  opt.seed = 3;
  const MonteCarloResult res = run_monte_carlo(opt);
  EXPECT_EQ(res.refused, 0U) << res.first_refusal;
  EXPECT_EQ(res.module_samples, 800U);
  EXPECT_LT(res.mae_position_m, 1e-12);  // m, i.e. 1e-9 mm
  EXPECT_LT(res.mae_steering_offset_rad, 1e-9);
  EXPECT_LT(res.mae_caster_offset_m, 1e-12);
  EXPECT_LT(res.mae_wheel_radius_m, 1e-12);
  EXPECT_LT(res.max_wheel_radius_m, 1e-10);
}

TEST(MonteCarlo, SameSeedSameResult) {
  MonteCarloOptions opt;
  opt.trials = 20;
  opt.seed = 9;
  opt.motion.position_noise_m = 1e-4;
  opt.motion.yaw_noise_rad = 1e-3;
  const MonteCarloResult a = run_monte_carlo(opt);
  const MonteCarloResult b = run_monte_carlo(opt);
  EXPECT_EQ(a.mae_position_m, b.mae_position_m);
  EXPECT_EQ(a.mae_wheel_radius_m, b.mae_wheel_radius_m);
  opt.seed = 10;
  EXPECT_NE(run_monte_carlo(opt).mae_position_m, a.mae_position_m);
}

TEST(MonteCarlo, NoisyRunReportsNoiseLevelErrorsAndCoverage) {
  MonteCarloOptions opt;
  opt.trials = 100;
  opt.motion.position_noise_m = 0.1e-3;
  opt.motion.yaw_noise_rad = 0.05 * std::numbers::pi / 180.0;
  const MonteCarloResult res = run_monte_carlo(opt);
  EXPECT_EQ(res.refused, 0U) << res.first_refusal;
  EXPECT_GT(res.mae_position_m, 1e-6);
  EXPECT_LT(res.mae_position_m, 1e-3);
  EXPECT_GE(res.coverage_3sigma, 0.95);
  // One entry per trial; their mean is the MAE (every trial has the same module count).
  ASSERT_EQ(res.trial_errors.size(), 100U);
  double mean_r = 0.0;
  for (const TrialErrors& t : res.trial_errors) mean_r += t.wheel_radius_m / 100.0;
  EXPECT_NEAR(mean_r, res.mae_wheel_radius_m, 1e-12);
}

}  // namespace
}  // namespace swivel::calibration
