// SPDX-License-Identifier: Apache-2.0
#pragma once
// Summary statistics of repeated simulated experiments: the mean with its standard error,
// the spread, and the relative change between two independent means (what the papers'
// tables report as a reduction). Plain functions; not real-time safe.

#include <cstddef>
#include <span>

namespace swivel::stats {

/// A value estimated from random draws, with its 1-sigma standard error.
struct Estimate {
  double value = 0.0;
  double standard_error = 0.0;
};

/// Mean, spread and order statistics of a sample.
struct Summary {
  std::size_t count = 0;
  double mean = 0.0;
  double standard_deviation = 0.0;  ///< sample (n - 1); 0 for fewer than two values
  double standard_error = 0.0;      ///< standard_deviation / sqrt(count)
  double min = 0.0;
  double lower_quartile = 0.0;  ///< quantile(0.25)
  double median = 0.0;
  double upper_quartile = 0.0;  ///< quantile(0.75)
  double max = 0.0;

  [[nodiscard]] Estimate mean_estimate() const { return {mean, standard_error}; }
};

/// @throws std::invalid_argument for an empty sample.
Summary summarize(std::span<const double> values);

/// The `q` quantile (0 <= q <= 1) of a sample, interpolated linearly between order
/// statistics at rank q (n - 1) (Hyndman and Fan's type 7, R's and NumPy's default): 0 is the
/// minimum, 0.5 the median, 1 the maximum.
/// @throws std::invalid_argument for an empty sample or q outside [0, 1].
double quantile(std::span<const double> values, double q);

/// The average of independent estimates (e.g. the means of equal-sized strata): the mean of
/// the values, its standard error sqrt(sum se^2) / n. @throws std::invalid_argument if empty.
Estimate average(std::span<const Estimate> estimates);

/// The relative change to / from - 1 of two independent estimates, with its standard error
/// to first order (delta method). A fraction: -0.6 is a 60 % reduction.
/// @throws std::invalid_argument when from.value is zero.
Estimate relative_change(const Estimate& from, const Estimate& to);

/// The relative change mean(to) / mean(from) - 1 of paired samples (to[i] and from[i] from
/// the same draw), with its first-order standard error: that of the mean of
/// (to[i] - ratio * from[i]) / mean(from). Pairing keeps what the two share out of the error.
/// @throws std::invalid_argument for empty or unequal samples, or a zero mean(from).
Estimate paired_relative_change(std::span<const double> from, std::span<const double> to);

}  // namespace swivel::stats
