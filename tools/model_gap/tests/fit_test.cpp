// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <functional>
#include <random>
#include <span>
#include <vector>

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

// A problem of `rows` rows, each its own window (residuals to be set).
FitProblem one_window_per_row(std::size_t rows) {
  FitProblem p;
  p.row_count = rows;
  p.window_count = rows;
  for (std::size_t k = 0; k < rows; ++k) p.row_window.push_back(k);
  return p;
}

// The decay's parameters a and b, from 0.5 within [0, 10].
std::vector<ParamSpec> decay_specs() {
  return {{"a", 0.5, 1.0, 0.0, 10.0}, {"b", 0.5, 1.0, 0.0, 10.0}};
}

TEST(FitTest, RecoversParametersWithinTheirUncertainty) {
  const Decay d = make_decay(2.0, 1.3, 1);
  const FitOutcome f = fit(decay_problem(d), decay_specs());
  ASSERT_TRUE(f.ok);
  ASSERT_TRUE(f.observable[0] && f.observable[1]);
  EXPECT_NEAR(f.values[0], 2.0, 4.0 * f.sigmas[0]);
  EXPECT_NEAR(f.values[1], 1.3, 4.0 * f.sigmas[1]);
  EXPECT_LT(f.sigmas[0], 0.01);
  EXPECT_NEAR(f.rss / static_cast<double>(f.n), 1.0, 0.2);
}

TEST(FitTest, BicPrefersTheTrueModelOverAnExtraParameter) {
  const Decay d = make_decay(2.0, 1.3, 2);
  const FitOutcome two = fit(decay_problem(d), decay_specs());
  // A third parameter that changes nothing only costs ln(n).
  FitProblem p3 = decay_problem(d);
  p3.residuals = [&d](std::span<const double> th, std::vector<double>& r) {
    r.resize(d.t.size());
    for (std::size_t k = 0; k < d.t.size(); ++k)
      r[k] = (d.y[k] - th[0] * std::exp(-th[1] * d.t[k])) / d.sigma;
    return th[2] == th[2];
  };
  std::vector<ParamSpec> specs = decay_specs();
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
      const FitOutcome f = fit(decay_problem(d), decay_specs());
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

// Many rows fix a spread Y a^2 + X b^2 (as a run fixes a module layout's), one row whose
// information is below 10^-6 of theirs pulls a towards 1.3: the solver drifts down the curved
// valley of equal spread, and putting the combination the run does not fix back at the anchors (1,
// 1) from there would land off the valley, worse than the anchors themselves. It is held there
// instead.
TEST(FitTest, ACombinationNotFixedIsHeldAtItsAnchorsWhereTheModelIsNotLinear) {
  constexpr double kY = 0.25;
  constexpr double kX = 0.75;
  constexpr double kSigma = 1e-4;
  constexpr std::size_t kRows = 200;
  const auto spread = [](double a, double b) { return kY * a * a + kX * b * b; };
  const double truth = spread(1.02, 1.0);
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<double> gain;
  std::vector<double> noise;
  for (std::size_t k = 0; k < kRows; ++k) {
    gain.push_back(1.0 + 0.5 * std::sin(0.1 * static_cast<double>(k)));
    noise.push_back(kSigma * gauss(rng));
  }
  FitProblem p = one_window_per_row(kRows + 1);
  p.residuals = [&](std::span<const double> th, std::vector<double>& r) {
    r.resize(kRows + 1);
    for (std::size_t k = 0; k < kRows; ++k)
      r[k] = (gain[k] * (spread(th[0], th[1]) - truth) - noise[k]) / kSigma;
    r[kRows] = 55.0 * (th[0] - 1.3);
    return true;
  };
  std::vector<ParamSpec> specs = {{"a", 1.0, 0.01, 0.5, 1.5}, {"b", 1.0, 0.01, 0.5, 1.5}};
  for (ParamSpec& s : specs) s.hold_when_unfixed = true;
  const FitOutcome f = fit(p, specs);
  ASSERT_TRUE(f.ok);
  EXPECT_FALSE(f.observable[0] || f.observable[1]);  // each has a part not fixed
  // On the valley: the rows fit to their noise (about kRows) plus the weak row's pull from
  // the anchors (about 270); put back from where the solver drifted, the fit would be worse
  // than 10^5.
  EXPECT_LT(f.rss, 2.0 * static_cast<double>(kRows) + 300.0);
  // The spread within 3 sigma (gradient (2 Y a, 2 X b) through the covariance), and within a
  // hundredth of a per cent.
  const double ga = 2.0 * kY * f.values[0];
  const double gb = 2.0 * kX * f.values[1];
  const std::vector<double>& c = f.covariance;
  const double sigma = std::sqrt(ga * ga * c[0] + 2.0 * ga * gb * c[1] + gb * gb * c[3]);
  EXPECT_NEAR(spread(f.values[0], f.values[1]), truth, 3.0 * sigma);
  EXPECT_NEAR(spread(f.values[0], f.values[1]), truth, 1e-4);
  // What stays unfixed is near the anchors, not where the weak row pulled.
  EXPECT_LT(std::abs(f.values[0] - 1.0), 0.05);
  EXPECT_LT(std::abs(f.values[1] - 1.0), 0.05);
}

// y = 2 x + offset + noise at the abscissae x_of(k).
struct Line {
  std::vector<double> x;
  std::vector<double> y;
};

Line noisy_line(std::size_t rows, const std::function<double(std::size_t)>& x_of, double offset,
                double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Line l;
  for (std::size_t k = 0; k < rows; ++k) {
    l.x.push_back(x_of(k));
    l.y.push_back(2.0 * l.x.back() + offset + sigma * gauss(rng));
  }
  return l;
}

// A parameter whose effect saturates (as a limit the run reaches at a few steps does): at the
// optimum the rows hardly depend on it, so the slope calls it unfixed, yet at its anchor the
// rows are far off. It is not a flat valley, and the optimum stands.
TEST(FitTest, AParameterTheSlopeCallsUnfixedStaysWhereTheAnchorWouldBreakTheFit) {
  constexpr double kSigma = 0.01;
  constexpr std::size_t kRows = 200;
  const Line line = noisy_line(
      kRows, [](std::size_t k) { return 0.01 * static_cast<double>(k); }, std::tanh(12.0), kSigma,
      5);
  const std::vector<double>& x = line.x;
  const std::vector<double>& y = line.y;
  FitProblem p = one_window_per_row(kRows);
  p.residuals = [&](std::span<const double> th, std::vector<double>& r) {
    r.resize(kRows);
    for (std::size_t k = 0; k < kRows; ++k)
      r[k] = (y[k] - th[0] * x[k] - std::tanh(th[1])) / kSigma;
    return true;
  };
  ParamSpec slope{"a", 1.0, 1.0, -10.0, 10.0};
  ParamSpec saturating{"b", 3.0, 1.0, 0.0, 20.0};
  saturating.anchor = 0.0;  // the model's own value: no effect at all
  const FitOutcome f = fit(p, {slope, saturating});
  ASSERT_TRUE(f.ok);
  EXPECT_FALSE(f.observable[1]);  // the slope at the optimum is below what counts as fixed
  EXPECT_GT(f.values[1],
            3.0);  // not at its anchor, where tanh(b) = 0 leaves the rows 100 sigma off
  EXPECT_LT(f.rss, 2.0 * static_cast<double>(kRows));
  EXPECT_NEAR(f.values[0], 2.0, 3.0 * f.sigmas[0]);
}

// A combination the rows barely fix, pulled away by one weak row: at its anchor the fit is a
// few units worse, far less than its whole noise. That is a weakly fixed combination, not a
// saturated one, and it goes back to its anchor (a run's weakest wheel-radius combination
// must not carry a significance it does not have).
TEST(FitTest, AWeaklyFixedCombinationThatDriftedGoesBackToItsAnchor) {
  constexpr double kSigma = 1e-3;
  constexpr std::size_t kRows = 200;
  const Line line = noisy_line(
      kRows, [](std::size_t k) { return 1.0 + 0.5 * std::sin(0.1 * static_cast<double>(k)); }, 0.0,
      kSigma, 9);
  const std::vector<double>& x = line.x;
  const std::vector<double>& y = line.y;
  FitProblem p = one_window_per_row(kRows + 1);
  p.residuals = [&](std::span<const double> th, std::vector<double>& r) {
    r.resize(kRows + 1);
    for (std::size_t k = 0; k < kRows; ++k) r[k] = (y[k] - th[0] * x[k]) / kSigma;
    r[kRows] = 10.0 * (th[1] - 1.3);  // information 100, against about 2.5e8 for a
    return true;
  };
  const FitOutcome f = fit(p, {{"a", 1.0, 1.0, -10.0, 10.0}, {"b", 1.0, 1.0, 0.0, 5.0}});
  ASSERT_TRUE(f.ok);
  EXPECT_FALSE(f.observable[1]);
  EXPECT_NEAR(f.values[1], 1.0, 1e-6);  // its anchor (the initial value), not 1.3
  // Anchored, the weak row adds 100 x 0.3^2 = 9 to a fit of about kRows.
  EXPECT_GT(f.rss, static_cast<double>(kRows) / 2.0 + 8.0);
  EXPECT_LT(f.rss, 2.0 * static_cast<double>(kRows));
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

// A Wald statistic whose covariance rests on few windows is judged against F: the same
// statistic means less on 5 windows than on a thousand, where F meets the chi-square. Student's
// t with 5 degrees of freedom has its two-sided 1 % point at 4.032.
TEST(FitTest, AWaldStatisticOnFewWindowsIsJudgedAgainstF) {
  EXPECT_NEAR(wald_f_z(25.0, 1.0, 1e7), chi_square_z(25.0, 1.0), 1e-3);
  EXPECT_NEAR(wald_f_z(4.032 * 4.032, 1.0, 5.0), 2.5758, 2e-3);
  EXPECT_LT(wald_f_z(25.0, 1.0, 5.0), wald_f_z(25.0, 1.0, 30.0));
  EXPECT_LT(wald_f_z(25.0, 1.0, 30.0), chi_square_z(25.0, 1.0));
  EXPECT_EQ(wald_f_z(25.0, 1.0, 0.5), 0.0);  // nothing left to judge the covariance by
  EXPECT_GT(wald_f_z(1e6, 2.0, 40.0), 8.0);  // far past double's tail: still ordered, large
}

// How many windows each coefficient's variance rests on: one that moves the residuals in 5 of
// 100 windows rests on 5; one that moves them alike in all rests on all (less the two fitted).
TEST(FitTest, TheWindowsACoefficientRestsOnAreCounted) {
  constexpr std::size_t kWindows = 100;
  constexpr std::size_t kRows = 4;  // per window
  std::vector<double> jacobian;
  std::vector<double> residuals;
  std::vector<std::size_t> row_window;
  std::vector<std::size_t> row_group;
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (std::size_t w = 0; w < kWindows; ++w) {
    for (std::size_t i = 0; i < kRows; ++i) {
      jacobian.push_back(1.0);
      jacobian.push_back(w % 20 == 0 ? 1.0 : 0.0);
      residuals.push_back(gauss(rng));
      row_window.push_back(w);
      row_group.push_back(i);
    }
  }
  std::vector<char> observable;
  std::vector<double> effective;
  (void)sandwich_covariance(jacobian, 2, residuals, row_window, row_group, kWindows, observable,
                            false, 0, &effective);
  ASSERT_EQ(effective.size(), 2U);
  EXPECT_NEAR(effective[0], kWindows - 2.0, 5.0);
  EXPECT_GT(effective[1], 5.0);  // a little more: the constant's estimate enters it too
  EXPECT_LT(effective[1], 6.0);
  EXPECT_EQ(fewest_windows(effective, 0, 2), effective[1]);
  EXPECT_EQ(fewest_windows(effective, 0, 1), effective[0]);
}

// The variance of a mean over windows whose residuals are the differences of one noisy pose,
// r_w = n_(w+1) - n_w (consecutive relative motions share the pose between them): with each
// window's score counted alone it is 2 sigma^2 / T, several times too much (the pose noise
// telescopes). Three lags of the scores with Bartlett weights leave 2 sigma^2 / (4 T), and
// leave white residuals' variance as it was.
double mean_variance(const std::vector<double>& residuals, std::size_t lags) {
  const std::vector<double> jacobian(residuals.size(), 1.0);
  std::vector<std::size_t> row_window(residuals.size());
  for (std::size_t w = 0; w < row_window.size(); ++w) row_window[w] = w;
  const std::vector<std::size_t> row_group(residuals.size(), 0);
  std::vector<char> observable;
  return sandwich_covariance(jacobian, 1, residuals, row_window, row_group, residuals.size(),
                             observable, false, lags)[0];
}

TEST(FitTest, LaggedScoresCountAPoseSharedByConsecutiveWindowsOnce) {
  constexpr std::size_t kWindows = 400;
  std::mt19937 rng(11);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<double> pose(kWindows + 1);
  for (double& n : pose) n = gauss(rng);
  std::vector<double> differenced(kWindows);
  std::vector<double> white(kWindows);
  for (std::size_t w = 0; w < kWindows; ++w) {
    differenced[w] = pose[w + 1] - pose[w];
    white[w] = gauss(rng);
  }
  const double shrink = mean_variance(differenced, 3) / mean_variance(differenced, 0);
  EXPECT_GT(shrink, 0.15);
  EXPECT_LT(shrink, 0.4);
  const double white_ratio = mean_variance(white, 3) / mean_variance(white, 0);
  EXPECT_GT(white_ratio, 0.7);
  EXPECT_LT(white_ratio, 1.3);
}

TEST(FitTest, NeweyWestBandwidthGrowsSlowlyWithTheWindows) {
  EXPECT_EQ(newey_west_lags(10), 2U);
  EXPECT_EQ(newey_west_lags(78), 3U);  // an 80 s run of 1 s windows
  EXPECT_EQ(newey_west_lags(100), 4U);
  EXPECT_EQ(newey_west_lags(1000), 6U);
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
