#pragma once
// Non-linear least squares over a handful of effect parameters (Ceres), with parameter
// uncertainty from the Jacobian at the optimum and the Bayesian information criterion.
// The residual function replays the whole run; rows are split into a training part (used
// by the fit) and a held-out validation part (only scored).

#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace swivel::model_gap {

/// One fitted parameter. The solver works on z = value / scale so that every parameter is
/// of order one; `scale` is the parameter's typical magnitude.
struct ParamSpec {
  std::string name;
  double initial = 0.0;
  double scale = 1.0;
  double lower = -1e300;
  double upper = 1e300;
};

/// Whitened residuals of the whole run for parameter values `theta` (same order as the
/// specs). Returns false when the replay cannot be evaluated for these values.
using ResidualFunction = std::function<bool(std::span<const double> theta, std::vector<double>& r)>;

struct FitProblem {
  ResidualFunction residuals;
  std::size_t row_count = 0;
  std::vector<char> is_training;      ///< per row: 1 = fitted, 0 = held out
  std::vector<std::size_t> row_group; ///< per row: channel index, rows of a group consecutive
};

struct FitOptions {
  int max_iterations = 15;
  double step = 1e-3;  ///< forward-difference step in z units (value / scale)
  double function_tolerance = 1e-5;
  double parameter_tolerance = 1e-6;
};

struct FitOutcome {
  bool ok = false;                ///< the solver ran and the optimum could be evaluated
  std::vector<double> values;
  std::vector<double> sigmas;     ///< 1-sigma, inflated for autocorrelated residuals
  std::vector<double> covariance; ///< p x p row-major, same units and inflation as sigmas
  double rss_training = 0.0;
  double rss_validation = 0.0;
  std::size_t n_training = 0;
  std::size_t n_validation = 0;
  double bic = 0.0;
  int iterations = 0;
  std::vector<double> residuals;  ///< all rows at the optimum
};

/// n ln(rss / n) + k ln(n): Gaussian residuals of unknown common variance.
double bic(double rss, std::size_t n, std::size_t k);

/// Scores fixed parameter values (no fitting): rss, bic with k = theta.size().
FitOutcome score(const FitProblem& problem, std::span<const double> theta);

/// Fits `specs` by Levenberg-Marquardt on the training rows.
FitOutcome fit(const FitProblem& problem, const std::vector<ParamSpec>& specs,
               const FitOptions& options = {});

/// sqrt(n / n_eff) for the training rows of `r`: how much the lag-one autocorrelation of
/// each group's residuals inflates a standard error computed as if they were independent.
double autocorrelation_inflation(const FitProblem& problem, const std::vector<double>& r);

}  // namespace swivel::model_gap
