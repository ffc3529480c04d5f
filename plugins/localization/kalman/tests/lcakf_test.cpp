// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/lcakf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace swivel::localization {
namespace {

TEST(Lcakf, SmoothsWhiteMeasurementNoiseOnConstantVelocity) {
  Lcakf kf;
  kf.set_noise(LcakfNoise{0.05, 0.02});
  kf.reset(0.0, 3.0, 0.0);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.02);
  const double dt = 0.01;
  const double vx = 0.3;
  double raw_sq = 0.0;
  double filtered_sq = 0.0;
  int n = 0;
  for (int i = 1; i <= 3000; ++i) {
    const double tx = vx * i * dt;
    const double zx = tx + noise(rng);
    const double zy = 3.0 + noise(rng);
    ASSERT_TRUE(kf.step(dt, zx, zy));
    if (i > 500) {
      raw_sq += (zx - tx) * (zx - tx);
      filtered_sq += (kf.x_m() - tx) * (kf.x_m() - tx);
      ++n;
    }
  }
  const double raw_rms = std::sqrt(raw_sq / n);
  const double filtered_rms = std::sqrt(filtered_sq / n);
  EXPECT_NEAR(raw_rms, 0.02, 0.002);
  EXPECT_LT(filtered_rms, 0.5 * raw_rms);
  EXPECT_NEAR(kf.vx_mps(), vx, 0.02);
  EXPECT_NEAR(kf.vy_mps(), 0.0, 0.02);
  EXPECT_GT(kf.covariance_x()(0, 0), 0.0);
  EXPECT_LT(kf.covariance_x()(0, 0), 0.02 * 0.02);
}

TEST(Lcakf, RejectsNonFiniteInput) {
  Lcakf kf;
  kf.reset(1.0, 2.0, 0.0);
  EXPECT_FALSE(kf.step(0.001, std::nan(""), 0.0));
  EXPECT_FALSE(kf.step(0.0, 1.0, 2.0));
  EXPECT_EQ(kf.x_m(), 1.0);
}

}  // namespace
}  // namespace swivel::localization
