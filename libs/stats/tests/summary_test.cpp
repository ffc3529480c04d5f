// SPDX-License-Identifier: Apache-2.0
// Summary statistics against values worked out by hand.

#include "swivel/stats/summary.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace swivel::stats {
namespace {

TEST(SummaryTest, MeanSpreadAndOrderStatisticsOfASmallSample) {
  const std::vector<double> v = {4.0, 1.0, 3.0, 2.0};
  const Summary s = summarize(v);
  EXPECT_EQ(s.count, 4U);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  // Squares about the mean: 2.25 + 0.25 + 0.25 + 2.25 = 5, over n - 1 = 3.
  EXPECT_DOUBLE_EQ(s.standard_deviation, std::sqrt(5.0 / 3.0));
  EXPECT_DOUBLE_EQ(s.standard_error, std::sqrt(5.0 / 3.0) / 2.0);
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.median, 2.5);  // even count: the mean of the middle two
  EXPECT_DOUBLE_EQ(s.max, 4.0);
}

TEST(SummaryTest, QuartilesInterpolateBetweenOrderStatistics) {
  // Sorted 1..9 (n = 9): q (n - 1) = 2 and 6 are exact ranks; 1..8 (n = 8): 1.75 and 5.25.
  const std::vector<double> nine = {9, 1, 8, 2, 7, 3, 6, 4, 5};
  const Summary s9 = summarize(nine);
  EXPECT_DOUBLE_EQ(s9.lower_quartile, 3.0);
  EXPECT_DOUBLE_EQ(s9.upper_quartile, 7.0);
  const std::vector<double> eight = {8, 1, 7, 2, 6, 3, 5, 4};
  const Summary s8 = summarize(eight);
  EXPECT_DOUBLE_EQ(s8.lower_quartile, 2.75);
  EXPECT_DOUBLE_EQ(s8.upper_quartile, 6.25);
  EXPECT_DOUBLE_EQ(quantile(eight, 0.5), s8.median);
  EXPECT_DOUBLE_EQ(quantile(eight, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(quantile(eight, 1.0), 8.0);
  EXPECT_DOUBLE_EQ(quantile(eight, 0.9), 7.3);  // rank 6.3: 7 + 0.3 (8 - 7)
  const std::vector<double> one = {7.0};
  EXPECT_DOUBLE_EQ(quantile(one, 0.25), 7.0);
  EXPECT_THROW(quantile(eight, 1.5), std::invalid_argument);
  EXPECT_THROW(quantile(std::vector<double>{}, 0.5), std::invalid_argument);
}

TEST(SummaryTest, OddCountMedianAndASingleValueHasNoSpread) {
  const std::vector<double> odd = {5.0, -1.0, 2.0};
  EXPECT_DOUBLE_EQ(summarize(odd).median, 2.0);
  const std::vector<double> one = {7.0};
  const Summary s = summarize(one);
  EXPECT_DOUBLE_EQ(s.mean, 7.0);
  EXPECT_DOUBLE_EQ(s.standard_error, 0.0);
  EXPECT_THROW(summarize(std::vector<double>{}), std::invalid_argument);
}

TEST(SummaryTest, StandardErrorMatchesTheScatterOfRepeatedMeans) {
  // Means of 25 draws of N(0, 2): their scatter over 2000 repeats is 2 / 5 = 0.4; the
  // standard error of each should agree with it on average.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 2.0);
  std::vector<double> means;
  double mean_se = 0.0;
  for (int r = 0; r < 2000; ++r) {
    std::vector<double> draws(25);
    for (double& d : draws) d = normal(rng);
    const Summary s = summarize(draws);
    means.push_back(s.mean);
    mean_se += s.standard_error / 2000.0;
  }
  EXPECT_NEAR(summarize(means).standard_deviation, 0.4, 0.02);
  EXPECT_NEAR(mean_se, 0.4, 0.02);
}

TEST(SummaryTest, AverageOfIndependentEstimates) {
  const std::vector<Estimate> e = {{1.0, 0.3}, {3.0, 0.4}};
  const Estimate a = average(e);
  EXPECT_DOUBLE_EQ(a.value, 2.0);
  EXPECT_DOUBLE_EQ(a.standard_error, 0.25);  // sqrt(0.09 + 0.16) / 2
  EXPECT_THROW(average(std::vector<Estimate>{}), std::invalid_argument);
}

TEST(SummaryTest, RelativeChangeAndItsFirstOrderError) {
  const Estimate c = relative_change({0.5, 0.01}, {0.2, 0.02});
  EXPECT_DOUBLE_EQ(c.value, -0.6);
  // ratio 0.4: sqrt((0.02 / 0.5)^2 + (0.4 * 0.01 / 0.5)^2) = sqrt(0.0016 + 0.000064).
  EXPECT_NEAR(c.standard_error, std::sqrt(0.0016 + 0.000064), 1e-15);
  EXPECT_THROW(relative_change({0.0, 0.1}, {1.0, 0.1}), std::invalid_argument);
}

TEST(SummaryTest, PairedRelativeChangeKeepsWhatThePairsShareOutOfTheError) {
  // Each "to" is 0.5 times its "from" up to +-0.01: the from values scatter widely, but the
  // halving is sharp, and only the pairing shows it.
  const std::vector<double> from = {1.0, 3.0, 2.0, 6.0};
  const std::vector<double> to = {0.51, 1.49, 1.01, 2.99};
  const Estimate paired = paired_relative_change(from, to);
  EXPECT_NEAR(paired.value, 6.0 / 12.0 - 1.0, 1e-12);
  const Estimate independent =
      relative_change(summarize(from).mean_estimate(), summarize(to).mean_estimate());
  EXPECT_DOUBLE_EQ(paired.value, independent.value);
  EXPECT_LT(paired.standard_error, 0.01);
  EXPECT_GT(independent.standard_error, 0.2);
  EXPECT_THROW(paired_relative_change(from, std::vector<double>{1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace swivel::stats
