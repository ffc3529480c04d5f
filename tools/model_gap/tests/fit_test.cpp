#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "swivel/model_gap/fit.hpp"

namespace swivel::model_gap {
namespace {

// y = a exp(-b t) + noise, whitened by the noise sigma.
struct Decay {
  std::vector<double> t;
  std::vector<double> y;
  double sigma = 0.01;
};

Decay make_decay(double a, double b, unsigned seed) {
  Decay d;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, d.sigma);
  for (int k = 0; k < 400; ++k) {
    d.t.push_back(0.01 * k);
    d.y.push_back(a * std::exp(-b * d.t.back()) + noise(rng));
  }
  return d;
}

FitProblem decay_problem(const Decay& d) {
  FitProblem p;
  p.row_count = d.t.size();
  p.residuals = [&d](std::span<const double> th, std::vector<double>& r) {
    r.resize(d.t.size());
    for (std::size_t k = 0; k < d.t.size(); ++k) {
      r[k] = (d.y[k] - th[0] * std::exp(-th[1] * d.t[k])) / d.sigma;
    }
    return true;
  };
  for (std::size_t k = 0; k < d.t.size(); ++k) p.is_training.push_back(d.t[k] < 2.8 ? 1 : 0);
  p.row_group.assign(d.t.size(), 0);
  return p;
}

TEST(FitTest, RecoversParametersWithinTheirUncertainty) {
  const Decay d = make_decay(2.0, 0.7, 3);
  const FitProblem p = decay_problem(d);
  const auto out = fit(p, {{"a", 1.0, 1.0}, {"b", 0.3, 1.0}});
  ASSERT_TRUE(out.ok);
  EXPECT_NEAR(out.values[0], 2.0, 4.0 * out.sigmas[0]);
  EXPECT_NEAR(out.values[1], 0.7, 4.0 * out.sigmas[1]);
  EXPECT_LT(out.sigmas[0], 0.01);
  EXPECT_GT(out.sigmas[0], 1e-4);
  // Whitened residuals of the true model: rss / n near 1.
  EXPECT_NEAR(out.rss_training / static_cast<double>(out.n_training), 1.0, 0.2);
  EXPECT_NEAR(out.rss_validation / static_cast<double>(out.n_validation), 1.0, 0.4);
}

TEST(FitTest, BicPrefersTheTrueModelOverAnExtraParameter) {
  const Decay d = make_decay(2.0, 0.7, 5);
  const FitProblem p = decay_problem(d);
  const auto two = fit(p, {{"a", 1.0, 1.0}, {"b", 0.3, 1.0}});
  // A third parameter the data do not need: an offset.
  FitProblem p3 = p;
  p3.residuals = [&d](std::span<const double> th, std::vector<double>& r) {
    r.resize(d.t.size());
    for (std::size_t k = 0; k < d.t.size(); ++k) {
      r[k] = (d.y[k] - th[0] * std::exp(-th[1] * d.t[k]) - th[2]) / d.sigma;
    }
    return true;
  };
  const auto three = fit(p3, {{"a", 1.0, 1.0}, {"b", 0.3, 1.0}, {"c", 0.0, 0.01}});
  EXPECT_LT(two.bic, three.bic);
  const std::vector<double> wrong{1.0, 0.7};
  EXPECT_LT(two.bic + 100.0, score(p, wrong).bic);
}

TEST(FitTest, CorrelatedResidualsInflateTheUncertainty) {
  FitProblem p;
  p.row_count = 1000;
  p.is_training.assign(1000, 1);
  p.row_group.assign(1000, 0);
  std::vector<double> smooth(1000);
  std::vector<double> white(1000);
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  double x = 0.0;
  for (std::size_t k = 0; k < 1000; ++k) {
    x = 0.95 * x + n(rng);
    smooth[k] = x;
    white[k] = n(rng);
  }
  EXPECT_NEAR(autocorrelation_inflation(p, white), 1.0, 0.1);
  EXPECT_NEAR(autocorrelation_inflation(p, smooth), std::sqrt(1.95 / 0.05), 1.5);
}

}  // namespace
}  // namespace swivel::model_gap
