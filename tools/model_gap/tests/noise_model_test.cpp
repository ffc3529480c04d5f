// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/noise_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace swivel::model_gap {
namespace {

// Residuals of variance a + b x for a spread of x: the fit recovers both, even with a few
// outlying windows mixed in.
TEST(NoiseModel, RecoversConstantAndMotionDependentParts) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> motion(0.0, 9.0);
  const double a = 4e-8;
  const double b = 1e-8;
  const std::size_t windows = 2000;
  std::vector<double> r(windows);
  std::vector<std::vector<double>> x(1, std::vector<double>(windows));
  for (std::size_t j = 0; j < windows; ++j) {
    x[0][j] = motion(rng);
    r[j] = std::sqrt(a + b * x[0][j]) * gauss(rng);
  }
  for (std::size_t j = 0; j < windows; j += 200) r[j] = 0.01;  // 10 jumps
  const NoiseModel m = estimate_noise(r, windows, x, {1e-12});
  EXPECT_NEAR(m.a[0], a, 0.25 * a);
  EXPECT_NEAR(m.b[0], b, 0.25 * b);
  EXPECT_NEAR(m.sigma(0, 4.0), std::sqrt(a + 4.0 * b), 0.1 * std::sqrt(a + 4.0 * b));
}

TEST(NoiseModel, NeverBelowTheSensorFloor) {
  const std::size_t windows = 50;
  std::vector<double> r(windows, 0.0);  // a perfect replay
  std::vector<std::vector<double>> x(1, std::vector<double>(windows, 1.0));
  const NoiseModel m = estimate_noise(r, windows, x, {1e-10});
  EXPECT_EQ(m.a[0], 1e-10);
  EXPECT_EQ(m.b[0], 0.0);
}

}  // namespace
}  // namespace swivel::model_gap
