// SPDX-License-Identifier: Apache-2.0
#include "swivel/stats/summary.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace swivel::stats {
namespace {

double sorted_quantile(const std::vector<double>& sorted, double q) {
  const double rank = q * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(rank));
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  const double fraction = rank - static_cast<double>(below);
  return sorted[below] + fraction * (sorted[above] - sorted[below]);
}

}  // namespace

double quantile(std::span<const double> values, double q) {
  if (values.empty()) throw std::invalid_argument("quantile: no values");
  if (!(q >= 0.0 && q <= 1.0)) throw std::invalid_argument("quantile: q outside [0, 1]");
  std::vector<double> sorted(values.begin(), values.end());
  std::sort(sorted.begin(), sorted.end());
  return sorted_quantile(sorted, q);
}

Summary summarize(std::span<const double> values) {
  if (values.empty()) throw std::invalid_argument("summarize: no values");
  Summary s;
  s.count = values.size();
  const auto n = static_cast<double>(s.count);
  double sum = 0.0;
  for (const double v : values) sum += v;
  s.mean = sum / n;
  if (s.count > 1) {
    double squares = 0.0;
    for (const double v : values) squares += (v - s.mean) * (v - s.mean);
    s.standard_deviation = std::sqrt(squares / (n - 1.0));
    s.standard_error = s.standard_deviation / std::sqrt(n);
  }
  std::vector<double> sorted(values.begin(), values.end());
  std::sort(sorted.begin(), sorted.end());
  s.min = sorted.front();
  s.max = sorted.back();
  const std::size_t mid = s.count / 2;
  s.median = s.count % 2 == 1 ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
  s.lower_quartile = sorted_quantile(sorted, 0.25);
  s.upper_quartile = sorted_quantile(sorted, 0.75);
  return s;
}

Estimate average(std::span<const Estimate> estimates) {
  if (estimates.empty()) throw std::invalid_argument("average: no estimates");
  const auto n = static_cast<double>(estimates.size());
  double sum = 0.0;
  double variance = 0.0;
  for (const Estimate& e : estimates) {
    sum += e.value;
    variance += e.standard_error * e.standard_error;
  }
  return {sum / n, std::sqrt(variance) / n};
}

Estimate relative_change(const Estimate& from, const Estimate& to) {
  if (from.value == 0.0) throw std::invalid_argument("relative_change: from a zero value");
  const double ratio = to.value / from.value;
  // d(ratio) = d(to) / from - ratio * d(from) / from, the two independent.
  const double se =
      std::hypot(to.standard_error / from.value, ratio * from.standard_error / from.value);
  return {ratio - 1.0, se};
}

Estimate paired_relative_change(std::span<const double> from, std::span<const double> to) {
  if (from.empty() || from.size() != to.size()) {
    throw std::invalid_argument("paired_relative_change: need two samples of one size");
  }
  const double from_mean = summarize(from).mean;
  if (from_mean == 0.0) throw std::invalid_argument("paired_relative_change: from a zero mean");
  const double ratio = summarize(to).mean / from_mean;
  std::vector<double> influence(from.size());
  for (std::size_t i = 0; i < from.size(); ++i) {
    influence[i] = (to[i] - ratio * from[i]) / from_mean;
  }
  return {ratio - 1.0, summarize(influence).standard_error};
}

}  // namespace swivel::stats
