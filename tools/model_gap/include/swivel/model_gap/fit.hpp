// SPDX-License-Identifier: Apache-2.0
#pragma once
// Non-linear least squares over a handful of effect parameters (Ceres), with a parameter
// covariance that stays honest when residuals are correlated in time: the sandwich
// (J'J)^-1 Omega (J'J)^-1. Slowly wandering noise, such as a wheel's random slip, makes
// neighbouring windows agree; an estimate that assumed them independent would be too sure
// of itself. Omega takes the windows' own scores at lag 0 (any correlation between channels
// of one window included) and, at longer lags, each channel's autocorrelation modelled as
// c phi^l (white noise plus a first-order process), fitted to its residuals. A kernel
// estimate on the scores alone (Newey-West) was tried and is far too sure of itself here: the
// effects' regressors are smooth over the run, and the scores of fitted residuals sum to
// zero.

#include <cstddef>
#include <functional>
#include <limits>
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
  /// Where a combination of parameters the run cannot fix is left (the nominal model's own
  /// value); NaN: at `initial`.
  double anchor = std::numeric_limits<double>::quiet_NaN();
  /// Lives on a scale unrelated to the effects' (a motion-capture body's offset): with such a
  /// parameter in a fit, the combinations the run does not fix are judged scale-free (on the
  /// information scaled to a unit diagonal), so that its units cannot hide an effect.
  bool scale_free = false;
  /// The residuals are not linear in this parameter along combinations the run may not fix
  /// (a module layout's turn rate goes with the square of its scales): the solver can drift
  /// far down such a combination's flat valley, and putting it back at the anchors from there
  /// lands off the valley. When that costs more than the noise (the whitened residual sum of
  /// squares rises by more than 1), the fit is solved again from there with the combinations
  /// not fixed held at the anchors.
  bool hold_when_unfixed = false;
};

/// Whitened residual rows for parameter values `theta` (same order as the specs); NaN for a
/// row without data. Returns false when the replay cannot be evaluated for these values.
using ResidualFunction = std::function<bool(std::span<const double> theta, std::vector<double>& r)>;

struct FitProblem {
  ResidualFunction residuals;
  std::size_t row_count = 0;
  std::vector<std::size_t> row_window;  ///< per row: its window (time order), for Omega
  std::vector<std::size_t> row_group;   ///< per row: its channel (one time series per group)
  std::size_t window_count = 0;
};

struct FitOptions {
  int max_iterations = 20;
  double step = 1e-3;  ///< forward-difference step in z units (value / scale)
  double function_tolerance = 1e-6;
  double parameter_tolerance = 1e-7;
};

struct FitOutcome {
  bool ok = false;  ///< the solver ran and the optimum could be evaluated
  std::vector<double> values;
  std::vector<double> sigmas;  ///< 1-sigma; infinite for a parameter the data cannot fix
  /// 1-sigma as if the rows were independent, s^2 (J'J)^-1: sigmas / naive_sigmas is how
  /// much the residuals' correlation widens each parameter's uncertainty.
  std::vector<double> naive_sigmas;
  std::vector<double> naive_covariance;  ///< p x p row-major, observable subspace
  std::vector<double> covariance;        ///< p x p row-major, observable subspace only
  std::vector<char> observable;          ///< per parameter
  /// The combinations the run does not fix (put back at their anchors), each a unit vector
  /// over the parameters in the fit's scaled units (value / ParamSpec::scale); `scales`
  /// turns them into the parameters' own units. A combination that mixes an effect with a
  /// nuisance leaves the effect's part of it open too (effects_part()).
  std::vector<std::vector<double>> unfixed;
  std::vector<double> scales;  ///< per parameter, ParamSpec::scale
  /// Per parameter: the windows its sandwich variance rests on (sandwich_covariance()).
  std::vector<double> effective_windows;
  double rss = 0.0;
  std::size_t n = 0;  ///< rows with data
  double bic = 0.0;
  int iterations = 0;
  std::vector<double> residuals;  ///< every row at the optimum
};

/// n ln(rss / n) + k ln(n): Gaussian residuals of unknown common variance.
double bic(double rss, std::size_t n, std::size_t k);

/// Scores fixed parameter values (no fitting): rss, bic with k = theta.size().
FitOutcome score(const FitProblem& problem, std::span<const double> theta);

/// Fits `specs` by Levenberg-Marquardt. Combinations of parameters the run hardly informs
/// (information below 1/1000 of the best-informed combination's: the residuals barely move
/// along them, so what little moves them is as likely the replay's own approximation as the
/// robot) are put back at their anchors and reported as not observable.
FitOutcome fit(const FitProblem& problem, const std::vector<ParamSpec>& specs,
               const FitOptions& options = {});

/// Sandwich covariance of least-squares coefficients: `jacobian` (rows x p, row-major) of the
/// whitened residuals `r` with respect to the coefficients; rows belong to time windows
/// (`row_window`) and to channels (`row_group`, one time series each). Rows with a non-finite
/// residual are skipped. Returns p x p row-major on the observable subspace; `observable`
/// flags the parameters the rows determine.
/// `scale_free`: judge the combinations not fixed on the information scaled to a unit diagonal
/// (ParamSpec::scale_free), else against the largest eigenvalue in the parameters' own units.
/// `score_lags`: how many lags of the windows' scores enter the middle of the sandwich
/// (Newey-West, Bartlett weights); past them, each channel's fitted first-order decay. 0: the
/// windows' scores as independent.
/// `effective_windows` (when given): per coefficient, the number of windows its variance in
/// effect rests on (Satterthwaite), the second degree of freedom of wald_f_z().
/// `unfixed` (when given): the combinations the rows do not fix, unit vectors over the
/// coefficients.
std::vector<double> sandwich_covariance(const std::vector<double>& jacobian, std::size_t p,
                                        const std::vector<double>& r,
                                        const std::vector<std::size_t>& row_window,
                                        const std::vector<std::size_t>& row_group,
                                        std::size_t window_count, std::vector<char>& observable,
                                        bool scale_free = false, std::size_t score_lags = 0,
                                        std::vector<double>* effective_windows = nullptr,
                                        std::vector<std::vector<double>>* unfixed = nullptr);

/// Newey and West's (1994) bandwidth for `windows` windows, 4 (T/100)^(2/9) lags rounded down:
/// 3 for an 80 s run of 1 s windows.
std::size_t newey_west_lags(std::size_t windows);

/// Significance of a chi-square statistic with `dof` degrees of freedom as the equivalent
/// normal deviate (from the exact upper tail, the regularized incomplete gamma function):
/// about 1 for a statistic at its mean, 5 for a one-in-
/// three-million event.
double chi_square_z(double chi2, double dof);

/// chi_square_z() for a Wald statistic whose covariance was estimated from the same data:
/// wald / rank against Fisher's F(rank, residual_dof), which a few dozen windows need (the
/// chi-square tail, its limit, is far too thin there).
double wald_f_z(double wald, double rank, double residual_dof);

/// The fewest windows any of the coefficients [first, first + count) rests on (0: none).
double fewest_windows(const std::vector<double>& effective_windows, std::size_t first,
                      std::size_t count);

/// d' C^+ d over the observable subspace of the covariance C (p x p row-major), and its
/// rank; d = values - reference.
double mahalanobis_squared(const std::vector<double>& difference,
                           const std::vector<double>& covariance, std::size_t& rank);

}  // namespace swivel::model_gap
