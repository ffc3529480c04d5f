// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace swivel::model_gap {
namespace {

// y = a exp(-b t) + noise, whitened by the noise sigma; one row per window.
struct Decay {
  std::vector<double> t;
  std::vector<double> y;
  double sigma = 0.01;
};

// White noise (rho = 0) or AR(1) noise of the same marginal spread.
Decay make_decay(double a, double b, unsigned seed, double rho = 0.0) {
  Decay d;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  double e = gauss(rng);
  for (int k = 0; k < 400; ++k) {
    d.t.push_back(0.01 * k);
    e = rho * e + std::sqrt(1.0 - rho * rho) * gauss(rng);
    d.y.push_back(a * std::exp(-b * d.t.back()) + d.sigma * e);
  }
  return d;
}

FitProblem decay_problem(const Decay& d) {
  FitProblem p;
  p.row_count = d.t.size();
  p.window_count = d.t.size();
  for (std::size_t k = 0; k < d.t.size(); ++k) p.row_window.push_back(k);
  p.residuals = [&d](std::span<const double> th, std::vector<double>& r) {
    r.resize(d.t.size());
    for (std::size_t k = 0; k < d.t.size(); ++k) {
      r[k] = (d.y[k] - th[0] * std::exp(-th[1] * d.t[k])) / d.sigma;
    }
    return true;
  };
  return p;
}

const std::vector<ParamSpec> kSpecs = {{"a", 0.5, 1.0, 0.0, 10.0}, {"b", 0.5, 1.0, 0.0, 10.0}};

TEST(FitTest, RecoversParametersWithinTheirUncertainty) {
  const Decay d = make_decay(2.0, 1.3, 1);
  const FitOutcome f = fit(decay_problem(d), kSpecs);
  ASSERT_TRUE(f.ok);
  ASSERT_TRUE(f.observable[0] && f.observable[1]);
  EXPECT_NEAR(f.values[0], 2.0, 4.0 * f.sigmas[0]);
  EXPECT_NEAR(f.values[1], 1.3, 4.0 * f.sigmas[1]);
  EXPECT_LT(f.sigmas[0], 0.01);
  EXPECT_NEAR(f.rss / static_cast<double>(f.n), 1.0, 0.2);
}

TEST(FitTest, BicPrefersTheTrueModelOverAnExtraParameter) {
  const Decay d = make_decay(2.0, 1.3, 2);
  const FitOutcome two = fit(decay_problem(d), kSpecs);
  // A third parameter that changes nothing only costs ln(n).
  FitProblem p3 = decay_problem(d);
  p3.residuals = [&d](std::span<const double> th, std::vector<double>& r) {
    r.resize(d.t.size());
    for (std::size_t k = 0; k < d.t.size(); ++k)
      r[k] = (d.y[k] - th[0] * std::exp(-th[1] * d.t[k])) / d.sigma;
    return th[2] == th[2];
  };
  std::vector<ParamSpec> specs = kSpecs;
  specs.push_back({"unused", 0.0, 1.0, -1.0, 1.0});
  const FitOutcome three = fit(p3, specs);
  EXPECT_LT(two.bic, three.bic);
  EXPECT_FALSE(three.observable[2]);  // the data do not fix it
  EXPECT_TRUE(std::isinf(three.sigmas[2]));
}

// Over many noise draws, about 68 % of the estimates fall within one reported sigma of the
// truth, for white and for strongly correlated noise (where the covariance must widen the
// intervals, which an independent-rows covariance would not).
TEST(FitTest, UncertaintiesAreCalibratedForWhiteAndCorrelatedNoise) {
  double white_sigma = 0.0;
  for (double rho : {0.0, 0.8}) {
    int within = 0;
    const int draws = 300;
    double mean_sigma = 0.0;
    for (int s = 0; s < draws; ++s) {
      // A slow decay spreads the information over the run, as the effects' regressors do.
      const Decay d = make_decay(2.0, 0.3, 100 + static_cast<unsigned>(s), rho);
      const FitOutcome f = fit(decay_problem(d), kSpecs);
      ASSERT_TRUE(f.ok);
      if (std::abs(f.values[0] - 2.0) <= f.sigmas[0]) ++within;
      mean_sigma += f.sigmas[0] / draws;
    }
    const double coverage = static_cast<double>(within) / draws;
    EXPECT_GT(coverage, 0.58) << "rho " << rho;
    EXPECT_LT(coverage, 0.80) << "rho " << rho;
    if (rho == 0.0) {
      white_sigma = mean_sigma;
    } else {
      EXPECT_GT(mean_sigma, 2.0 * white_sigma);  // about sqrt((1 + rho) / (1 - rho)) = 3 times
    }
  }
}

TEST(FitTest, ChiSquareAsANormalDeviate) {
  // One degree of freedom: the deviate itself.
  for (double z : {0.5, 1.0, 3.0, 5.0, 12.0, 40.0})
    EXPECT_NEAR(chi_square_z(z * z, 1.0), z, 1e-6 * z) << z;
  // Two: the tail is exp(-chi2 / 2); at chi2 = 2 ln(1 / 0.0455) it matches 2 sigma.
  EXPECT_NEAR(chi_square_z(2.0 * std::log(1.0 / 0.0455003), 2.0), 2.0, 1e-4);
  EXPECT_GT(chi_square_z(60.0, 4.0), 6.0);
  EXPECT_LT(chi_square_z(4.0, 4.0), 1.0);  // a statistic at its mean
  EXPECT_EQ(chi_square_z(0.0, 3.0), 0.0);
}

TEST(FitTest, MahalanobisUsesOnlyTheObservableSubspace) {
  // Variance 4 along (1, 1) / sqrt(2), nothing along (1, -1).
  const std::vector<double> cov = {2.0, 2.0, 2.0, 2.0};
  std::size_t rank = 0;
  EXPECT_NEAR(mahalanobis_squared({2.0, 2.0}, cov, rank), 2.0, 1e-9);  // |d| = 2 sqrt 2, sigma 2
  EXPECT_EQ(rank, 1U);
  EXPECT_NEAR(mahalanobis_squared({1.0, -1.0}, cov, rank), 0.0, 1e-9);
}

}  // namespace
}  // namespace swivel::model_gap
