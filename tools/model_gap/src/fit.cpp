// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/fit.hpp"

#include <ceres/ceres.h>
#include <ceres/normal_prior.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>
#include <limits>
#include <numbers>

namespace swivel::model_gap {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Eigenvalues of a covariance below this share of the largest are directions it leaves out.
constexpr double kRankTolerance = 1e-9;
// Eigenvalues of J'J, scaled to a unit diagonal, below this share of the largest are
// combinations the run does not inform enough to fix.
constexpr double kWeakInformation = 1e-3;
// A parameter whose information is below this share of the best-informed one's has none.
constexpr double kNoInformation = 1e-14;

// The information J'J (z units) split into the combinations the run fixes and those it does
// not. It is judged scaled to a unit diagonal, y = z / d with d = 1 / sqrt(diag): each
// parameter against its own spread, so that how strongly one parameter acts (a lever arm of a
// centimetre against a scale of a permille) cannot make another look uninformed; combinations
// that trade against each other still show as small eigenvalues. A parameter with no
// information at all is a combination not fixed (one barely informed keeps its wide sigma).
struct InformationSplit {
  Eigen::VectorXd d;           ///< z = d .* y
  Eigen::MatrixXd inverse;     ///< pseudo-inverse of J'J on the fixed combinations, z units
  Eigen::MatrixXd null_space;  ///< projector onto the combinations not fixed, y units
};

InformationSplit split_information(const Eigen::MatrixXd& information, bool scale_free) {
  const Eigen::Index p = information.rows();
  InformationSplit out;
  out.d = Eigen::VectorXd::Ones(p);
  if (!scale_free) {
    // In the parameters' own units (z: value / typical magnitude).
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(information);
    const double top = std::max(eig.eigenvalues().maxCoeff(), 0.0);
    out.inverse = Eigen::MatrixXd::Zero(p, p);
    out.null_space = Eigen::MatrixXd::Zero(p, p);
    for (Eigen::Index k = 0; k < p; ++k) {
      const Eigen::VectorXd v = eig.eigenvectors().col(k);
      const double lambda = eig.eigenvalues()(k);
      if (lambda > kWeakInformation * top && lambda > 0.0) {
        out.inverse += v * v.transpose() / lambda;
      } else {
        out.null_space += v * v.transpose();
      }
    }
    return out;
  }
  const double largest = p > 0 ? information.diagonal().maxCoeff() : 0.0;
  const auto informed = [&information, largest](Eigen::Index a) {
    return information(a, a) > kNoInformation * largest && information(a, a) > 0.0;
  };
  for (Eigen::Index a = 0; a < p; ++a) {
    if (informed(a)) out.d(a) = 1.0 / std::sqrt(information(a, a));
  }
  Eigen::MatrixXd scaled = out.d.asDiagonal() * information * out.d.asDiagonal();
  for (Eigen::Index a = 0; a < p; ++a) {
    if (!informed(a)) {
      scaled.row(a).setZero();
      scaled.col(a).setZero();
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  const double top = std::max(eig.eigenvalues().maxCoeff(), 0.0);
  Eigen::MatrixXd inverse_y = Eigen::MatrixXd::Zero(p, p);
  out.null_space = Eigen::MatrixXd::Zero(p, p);
  for (Eigen::Index k = 0; k < p; ++k) {
    const Eigen::VectorXd v = eig.eigenvectors().col(k);
    const double lambda = eig.eigenvalues()(k);
    if (lambda > kWeakInformation * top && lambda > 0.0) {
      inverse_y += v * v.transpose() / lambda;
    } else {
      out.null_space += v * v.transpose();
    }
  }
  out.inverse = out.d.asDiagonal() * inverse_y * out.d.asDiagonal();
  return out;
}

// Every row; rows without data (NaN) count as zero so that the residual vector keeps a
// fixed size. Forward differences with a fixed step in z: the replay is smooth in its
// parameters, and a step tied to |z| would collapse at z = 0, where many fits start.
class ReplayCost final : public ceres::CostFunction {
 public:
  ReplayCost(const FitProblem& problem, const std::vector<ParamSpec>& specs, double step)
      : problem_(problem), specs_(specs), step_(step), theta_(specs.size()), z_(specs.size()) {
    set_num_residuals(static_cast<int>(problem.row_count));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(specs.size()));
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const std::size_t p = specs_.size();
    for (std::size_t j = 0; j < p; ++j) z_[j] = parameters[0][j];
    if (!evaluate_at(residuals)) return false;
    if (jacobians == nullptr || jacobians[0] == nullptr) return true;
    const std::size_t rows = problem_.row_count;
    shifted_.resize(rows);
    for (std::size_t j = 0; j < p; ++j) {
      // Step inwards when a bound is within reach.
      double h = step_;
      if (z_[j] + h > specs_[j].upper / specs_[j].scale) h = -h;
      const double saved = z_[j];
      z_[j] = saved + h;
      const bool ok = evaluate_at(shifted_.data());
      z_[j] = saved;
      if (!ok) return false;
      for (std::size_t i = 0; i < rows; ++i) {
        jacobians[0][i * p + j] = (shifted_[i] - residuals[i]) / h;
      }
    }
    return true;
  }

 private:
  bool evaluate_at(double* out) const {
    for (std::size_t j = 0; j < specs_.size(); ++j) theta_[j] = z_[j] * specs_[j].scale;
    if (!problem_.residuals(theta_, buffer_)) return false;
    for (std::size_t i = 0; i < problem_.row_count; ++i) {
      const double r = buffer_[i];
      out[i] = std::isfinite(r) ? r : 0.0;
    }
    return true;
  }

  const FitProblem& problem_;
  const std::vector<ParamSpec>& specs_;
  double step_;
  mutable std::vector<double> theta_;
  mutable std::vector<double> z_;
  mutable std::vector<double> buffer_;
  mutable std::vector<double> shifted_;
};

}  // namespace

double bic(double rss, std::size_t n, std::size_t k) {
  if (n == 0) return 0.0;
  const auto nn = static_cast<double>(n);
  return nn * std::log(std::max(rss, 1e-300) / nn) + static_cast<double>(k) * std::log(nn);
}

namespace {

// ln Q(a, x), the regularized upper incomplete gamma function: a series for P below a + 1,
// a continued fraction (modified Lentz) for Q above, kept in logarithms so that the tail of a
// strong signal does not underflow.
double log_upper_gamma(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefix = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < 500 && std::abs(term) > 1e-16 * std::abs(sum); ++n) {
      term *= x / (a + n);
      sum += term;
    }
    const double p = std::exp(log_prefix) * sum;
    return std::log1p(-std::min(p, 1.0 - 1e-300));
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < 500; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-15) break;
  }
  return log_prefix + std::log(h);
}

// ln erfc(y), with the asymptotic series where erfc underflows.
double log_erfc(double y) {
  if (y < 25.0) return std::log(std::erfc(y));
  const double y2 = y * y;
  return -y2 - std::log(y * std::sqrt(std::numbers::pi)) + std::log1p(-0.5 / y2 + 0.75 / (y2 * y2));
}

}  // namespace

namespace {

// The |z| of a normal deviate with the same two-sided tail as ln p: erfc(z / sqrt 2) = p, by
// Newton's method on ln erfc from the first terms of its asymptotic inverse.
double z_of_log_tail(double log_p) {
  if (log_p >= 0.0) return 0.0;
  double z = std::sqrt(std::max(0.0, -2.0 * log_p - std::log(std::max(-2.0 * log_p, 1.0))));
  for (int i = 0; i < 50; ++i) {
    const double y = z / std::sqrt(2.0);
    const double f = log_erfc(y) - log_p;
    // d/dz ln erfc(z / sqrt 2) = -sqrt(2 / pi) exp(-z^2 / 2) / erfc(z / sqrt 2)
    const double slope = -std::sqrt(2.0 / std::numbers::pi) * std::exp(-0.5 * z * z - log_erfc(y));
    const double step = f / slope;
    z = std::max(0.0, z - step);
    if (std::abs(step) < 1e-12) break;
  }
  return z;
}

}  // namespace

double chi_square_z(double chi2, double dof) {
  if (!(dof > 0.0) || !(chi2 > 0.0)) return 0.0;
  if (!std::isfinite(chi2)) return std::numeric_limits<double>::infinity();
  return z_of_log_tail(log_upper_gamma(0.5 * dof, 0.5 * chi2));
}

double wald_f_z(double wald, double rank, double residual_dof) {
  if (!(rank > 0.0) || !(wald > 0.0)) return 0.0;
  if (!std::isfinite(wald)) return std::numeric_limits<double>::infinity();
  if (!(residual_dof >= 1.0)) return 0.0;  // nothing left to estimate the covariance from
  // Errors answered with a value (NaN, 0), never an exception.
  using Policy = boost::math::policies::policy<
      boost::math::policies::domain_error<boost::math::policies::ignore_error>,
      boost::math::policies::overflow_error<boost::math::policies::ignore_error>,
      boost::math::policies::evaluation_error<boost::math::policies::ignore_error>>;
  const boost::math::fisher_f_distribution<double, Policy> f(rank, residual_dof);
  const double p = boost::math::cdf(boost::math::complement(f, wald / rank));
  // Past double's range the tail is beyond any threshold; the chi-square conversion (which
  // the F tail approaches from below) keeps the order of such statistics.
  if (!(p > 0.0)) return chi_square_z(wald, rank);
  return z_of_log_tail(std::log(p));
}

double fewest_windows(const std::vector<double>& effective_windows, std::size_t first,
                      std::size_t count) {
  double fewest = std::numeric_limits<double>::infinity();
  for (std::size_t k = first; k < first + count && k < effective_windows.size(); ++k) {
    if (effective_windows[k] > 0.0) fewest = std::min(fewest, effective_windows[k]);
  }
  return std::isfinite(fewest) ? fewest : 0.0;
}

double mahalanobis_squared(const std::vector<double>& difference,
                           const std::vector<double>& covariance, std::size_t& rank) {
  const auto p = static_cast<Eigen::Index>(difference.size());
  rank = 0;
  if (p == 0) return 0.0;
  Eigen::MatrixXd c(p, p);
  Eigen::VectorXd d(p);
  for (Eigen::Index a = 0; a < p; ++a) {
    d(a) = difference[static_cast<std::size_t>(a)];
    for (Eigen::Index b = 0; b < p; ++b) c(a, b) = covariance[static_cast<std::size_t>(a * p + b)];
  }
  if (!c.allFinite() || !d.allFinite()) return kInf;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (c + c.transpose()));
  const double top = std::max(eig.eigenvalues().maxCoeff(), 0.0);
  double sum = 0.0;
  for (Eigen::Index k = 0; k < p; ++k) {
    const double lambda = eig.eigenvalues()(k);
    if (!(lambda > kRankTolerance * top) || !(lambda > 0.0)) continue;
    const double proj = eig.eigenvectors().col(k).dot(d);
    sum += proj * proj / lambda;
    ++rank;
  }
  return sum;
}

namespace {

// Autocorrelation of one channel's residual series modelled as c phi^l for lags l >= 1 (a
// white part and a first-order part): fitted log-linearly to the lags that stand out of the
// estimate's own noise, none when lag one does not.
struct Autocorrelation {
  double c = 0.0;
  double phi = 0.0;
};

Autocorrelation fit_autocorrelation(const std::vector<double>& series) {
  constexpr std::size_t kLags = 5;
  double s2 = 0.0;
  double n = 0.0;
  for (double v : series) {
    if (!std::isfinite(v)) continue;
    s2 += v * v;
    n += 1.0;
  }
  Autocorrelation out;
  if (n < 20.0 || s2 <= 0.0) return out;
  s2 /= n;
  std::array<double, kLags + 1> rho{};
  for (std::size_t l = 1; l <= kLags; ++l) {
    double s = 0.0;
    for (std::size_t i = l; i < series.size(); ++i) {
      if (std::isfinite(series[i]) && std::isfinite(series[i - l])) s += series[i] * series[i - l];
    }
    rho[l] = s / (n * s2);
  }
  const double noise = 1.0 / std::sqrt(n);
  if (!(rho[1] > 2.0 * noise)) return out;
  double sx = 0.0;
  double sy = 0.0;
  double sxx = 0.0;
  double sxy = 0.0;
  double m = 0.0;
  for (std::size_t l = 1; l <= kLags && rho[l] > noise; ++l) {
    const auto x = static_cast<double>(l);
    sx += x;
    sy += std::log(rho[l]);
    sxx += x * x;
    sxy += x * std::log(rho[l]);
    m += 1.0;
  }
  out.phi = m >= 2.0 ? std::exp((m * sxy - sx * sy) / (m * sxx - sx * sx)) : rho[1];
  out.phi = std::clamp(out.phi, 0.0, 0.97);
  out.c = out.phi > 0.0 ? std::clamp(rho[1] / out.phi, 0.0, 1.0) : 0.0;
  return out;
}

}  // namespace

namespace {

// Per coefficient: how many windows its sandwich variance rests on, (sum_w V_w)^2 / sum_w V_w^2
// with V_w = sum over the window's rows of (B^-1 J_i)^2, the window's share of the variance
// were the rows independent with equal noise (Satterthwaite's degrees of freedom of a sum of
// squares).
std::vector<double> satterthwaite_windows(const std::vector<double>& jacobian, std::size_t p,
                                          const std::vector<double>& r,
                                          const std::vector<std::size_t>& row_window,
                                          std::size_t window_count,
                                          const Eigen::MatrixXd& inverse) {
  const auto pp = static_cast<Eigen::Index>(p);
  Eigen::MatrixXd share = Eigen::MatrixXd::Zero(pp, static_cast<Eigen::Index>(window_count));
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (!std::isfinite(r[i])) continue;
    const Eigen::Map<const Eigen::VectorXd> row(jacobian.data() + i * p, pp);
    share.col(static_cast<Eigen::Index>(row_window[i])) +=
        (inverse * row).array().square().matrix();
  }
  // At most the windows with data less the coefficients.
  const double windows =
      static_cast<double>((share.colwise().sum().array() > 0.0).count()) - static_cast<double>(p);
  std::vector<double> out(p, 0.0);
  for (Eigen::Index k = 0; k < pp; ++k) {
    const double sum = share.row(k).sum();
    const double sum_sq = share.row(k).squaredNorm();
    out[static_cast<std::size_t>(k)] = sum_sq > 0.0 ? std::min(sum * sum / sum_sq, windows) : 0.0;
  }
  return out;
}

constexpr auto kNoRow = static_cast<std::size_t>(-1);

// Newey and West's lagged products of the windows' scores with Bartlett weights, 1 - l/(L+1):
// consecutive windows' relative motions share the pose between them, with opposite signs, and
// what the replay leaves of a manoeuvre (creep while speeding up, given back while slowing
// down) cancels over a few windows. The products of each window's score alone count both as
// independent noise, several times what reaches the estimate. The weights keep omega positive
// semi-definite.
void add_score_lags(const Eigen::MatrixXd& scores, const std::vector<char>& used, std::size_t lags,
                    Eigen::MatrixXd& omega) {
  const auto windows = static_cast<std::size_t>(scores.cols());
  for (std::size_t l = 1; l <= lags && l < windows; ++l) {
    const double weight = 1.0 - static_cast<double>(l) / static_cast<double>(lags + 1);
    Eigen::MatrixXd cross = Eigen::MatrixXd::Zero(scores.rows(), scores.rows());
    for (std::size_t j = l; j < windows; ++j) {
      if (used[j] == 0 || used[j - l] == 0) continue;
      cross.noalias() += scores.col(static_cast<Eigen::Index>(j)) *
                         scores.col(static_cast<Eigen::Index>(j - l)).transpose();
    }
    omega += weight * (cross + cross.transpose());
  }
}

// One channel's fitted decay c phi^l (the lag's share of its variance) in omega, where the
// scores' own lags do not hold it: the part their Bartlett weights leave out, l / (L + 1), and
// every lag past them. `rows`: the channel's row in each window, kNoRow where it has none.
void add_channel_decay(const std::vector<double>& jacobian, std::size_t p,
                       const std::vector<double>& r, const std::vector<std::size_t>& rows,
                       std::size_t score_lags, Eigen::MatrixXd& omega) {
  const auto pp = static_cast<Eigen::Index>(p);
  const std::size_t window_count = rows.size();
  std::vector<double> series(window_count, std::numeric_limits<double>::quiet_NaN());
  double s2 = 0.0;
  double n = 0.0;
  for (std::size_t j = 0; j < window_count; ++j) {
    if (rows[j] == kNoRow) continue;
    series[j] = r[rows[j]];
    s2 += series[j] * series[j];
    n += 1.0;
  }
  const Autocorrelation ac = fit_autocorrelation(series);
  if (ac.c <= 0.0 || n == 0.0) return;
  s2 /= n;
  for (std::size_t l = 1; l < window_count; ++l) {
    const double decay = ac.c * std::pow(ac.phi, static_cast<double>(l));
    if (decay <= 1e-4) break;
    const double weight = l <= score_lags
                              ? decay * static_cast<double>(l) / static_cast<double>(score_lags + 1)
                              : decay;
    Eigen::MatrixXd cross = Eigen::MatrixXd::Zero(pp, pp);
    for (std::size_t j = l; j < window_count; ++j) {
      const std::size_t a = rows[j];
      const std::size_t b = rows[j - l];
      if (a == kNoRow || b == kNoRow) continue;
      const Eigen::Map<const Eigen::VectorXd> ja(jacobian.data() + a * p, pp);
      const Eigen::Map<const Eigen::VectorXd> jb(jacobian.data() + b * p, pp);
      cross.noalias() += ja * jb.transpose();
    }
    omega += weight * s2 * (cross + cross.transpose());
  }
}

// The null space's directions over the coefficients themselves (the split judges them on the
// information scaled by d), as unit vectors.
std::vector<std::vector<double>> unfixed_directions(const InformationSplit& split) {
  std::vector<std::vector<double>> out;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(split.null_space);
  for (Eigen::Index k = 0; k < eig.eigenvalues().size(); ++k) {
    if (!(eig.eigenvalues()(k) > 0.5)) continue;  // a projector's eigenvalues are 0 or 1
    Eigen::VectorXd v = split.d.cwiseProduct(eig.eigenvectors().col(k));
    if (!(v.norm() > 0.0)) continue;
    v.normalize();
    out.emplace_back(v.data(), v.data() + v.size());
  }
  return out;
}

}  // namespace

std::size_t newey_west_lags(std::size_t windows) {
  return static_cast<std::size_t>(
      std::floor(4.0 * std::pow(static_cast<double>(windows) / 100.0, 2.0 / 9.0)));
}

std::vector<double> sandwich_covariance(const std::vector<double>& jacobian, std::size_t p,
                                        const std::vector<double>& r,
                                        const std::vector<std::size_t>& row_window,
                                        const std::vector<std::size_t>& row_group,
                                        std::size_t window_count, std::vector<char>& observable,
                                        bool scale_free, std::size_t score_lags,
                                        std::vector<double>* effective_windows,
                                        std::vector<std::vector<double>>* unfixed) {
  const auto pp = static_cast<Eigen::Index>(p);
  Eigen::MatrixXd bread = Eigen::MatrixXd::Zero(pp, pp);
  Eigen::MatrixXd scores = Eigen::MatrixXd::Zero(pp, static_cast<Eigen::Index>(window_count));
  std::size_t groups = 0;
  for (std::size_t g : row_group) groups = std::max(groups, g + 1);
  // Per group: its rows by window (kNoRow where it has none).
  std::vector<std::vector<std::size_t>> rows_of(groups,
                                                std::vector<std::size_t>(window_count, kNoRow));
  std::vector<char> used(window_count, 0);
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (!std::isfinite(r[i])) continue;
    const Eigen::Map<const Eigen::VectorXd> row(jacobian.data() + i * p, pp);
    bread.noalias() += row * row.transpose();
    scores.col(static_cast<Eigen::Index>(row_window[i])) += row * r[i];
    used[row_window[i]] = 1;
    rows_of[row_group[i]][row_window[i]] = i;
  }
  Eigen::MatrixXd omega = scores * scores.transpose();
  add_score_lags(scores, used, score_lags, omega);
  for (const std::vector<std::size_t>& rows : rows_of) {
    add_channel_decay(jacobian, p, r, rows, score_lags, omega);
  }
  const double windows = static_cast<double>(std::count(used.begin(), used.end(), 1));
  if (windows > static_cast<double>(p) + 1.0) omega *= windows / (windows - static_cast<double>(p));

  const InformationSplit split = split_information(bread, scale_free);
  const Eigen::MatrixXd& inverse = split.inverse;
  const Eigen::MatrixXd& null_space = split.null_space;
  const Eigen::MatrixXd cov = inverse * omega * inverse;
  if (unfixed != nullptr) *unfixed = unfixed_directions(split);
  if (effective_windows != nullptr) {
    *effective_windows = satterthwaite_windows(jacobian, p, r, row_window, window_count, inverse);
    // Lagged products make a variance spread over the run rest on fewer independent pieces:
    // about 1.5 T / S of them for the Bartlett kernel over S = lags + 1 windows (Andrews
    // 1991). One that rests on a few windows apart keeps their count.
    if (score_lags > 0) {
      const double pieces = 1.5 * windows / static_cast<double>(score_lags + 1);
      for (double& w : *effective_windows) w = std::min(w, pieces);
    }
  }
  observable.assign(p, 1);
  std::vector<double> out(p * p);
  for (Eigen::Index a = 0; a < pp; ++a) {
    // A parameter with a sizeable part in a direction the data do not fix is not observable
    // on its own (e.g. one radius of a diagonal pattern on a four-caster robot).
    if (null_space(a, a) > 0.01) observable[static_cast<std::size_t>(a)] = 0;
    for (Eigen::Index b = 0; b < pp; ++b) out[static_cast<std::size_t>(a * pp + b)] = cov(a, b);
  }
  return out;
}

FitOutcome score(const FitProblem& problem, std::span<const double> theta) {
  FitOutcome out;
  out.values.assign(theta.begin(), theta.end());
  out.sigmas.assign(theta.size(), kInf);
  out.naive_sigmas.assign(theta.size(), kInf);
  out.observable.assign(theta.size(), 0);
  if (!problem.residuals(theta, out.residuals)) return out;
  for (double v : out.residuals) {
    if (!std::isfinite(v)) continue;
    out.rss += v * v;
    ++out.n;
  }
  out.ok = true;
  out.bic = bic(out.rss, out.n, theta.size());
  return out;
}

namespace {

ceres::Solver::Options solver_options_of(const FitOptions& options) {
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  return solver_options;
}

// The Jacobian (rows x p, row-major) of a sparse one.
std::vector<double> dense_jacobian(const ceres::CRSMatrix& jac, std::size_t p) {
  std::vector<double> dense(static_cast<std::size_t>(jac.num_rows) * p, 0.0);
  for (int r = 0; r < jac.num_rows; ++r) {
    for (int k = jac.rows[static_cast<std::size_t>(r)];
         k < jac.rows[static_cast<std::size_t>(r) + 1]; ++k) {
      dense[static_cast<std::size_t>(r) * p +
            static_cast<std::size_t>(jac.cols[static_cast<std::size_t>(k)])] =
          jac.values[static_cast<std::size_t>(k)];
    }
  }
  return dense;
}

// J'J of a Jacobian (`rows` x p, row-major).
Eigen::MatrixXd information_of(const std::vector<double>& dense, int rows, std::size_t p) {
  const auto pp = static_cast<Eigen::Index>(p);
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(pp, pp);
  for (int r = 0; r < rows; ++r) {
    const Eigen::Map<const Eigen::VectorXd> row(dense.data() + static_cast<std::size_t>(r) * p, pp);
    information.noalias() += row * row.transpose();
  }
  return information;
}

// Combinations the run barely informs go back to their anchors (z: the optimum, z units;
// `dense`: its Jacobian with `rows` rows).
void anchor_uninformed(const std::vector<double>& dense, int rows,
                       const std::vector<ParamSpec>& specs, bool scale_free,
                       std::vector<double>& z) {
  const std::size_t p = specs.size();
  const auto pp = static_cast<Eigen::Index>(p);
  const InformationSplit split = split_information(information_of(dense, rows, p), scale_free);
  Eigen::VectorXd offset(pp);
  for (std::size_t j = 0; j < p; ++j) {
    const double anchor = std::isfinite(specs[j].anchor) ? specs[j].anchor : specs[j].initial;
    offset(static_cast<Eigen::Index>(j)) = z[j] - anchor / specs[j].scale;
  }
  // The part of the offset (in y units) along the combinations not fixed, back in z units.
  const Eigen::VectorXd removed =
      split.d.asDiagonal() * (split.null_space * split.d.cwiseInverse().asDiagonal() * offset);
  if (removed.norm() > 0.0) {
    for (std::size_t j = 0; j < p; ++j) {
      z[j] = std::clamp(z[j] - removed(static_cast<Eigen::Index>(j)),
                        specs[j].lower / specs[j].scale, specs[j].upper / specs[j].scale);
    }
  }
}

// A prior that holds the combinations `dense` barely informs at `anchor` (z units), as strongly
// as the run fixes its best-informed one: A = sqrt(top) N / d, with N the projector onto them
// (y units).
ceres::CostFunction* hold_uninformed(const std::vector<double>& dense, int rows,
                                     const std::vector<ParamSpec>& specs, bool scale_free) {
  const std::size_t p = specs.size();
  const Eigen::MatrixXd information = information_of(dense, rows, p);
  const InformationSplit split = split_information(information, scale_free);
  const Eigen::MatrixXd scaled = split.d.asDiagonal() * information * split.d.asDiagonal();
  const double top = std::max(
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scaled).eigenvalues().maxCoeff(), 0.0);
  Eigen::VectorXd anchor(static_cast<Eigen::Index>(p));
  for (std::size_t j = 0; j < p; ++j) {
    const double a = std::isfinite(specs[j].anchor) ? specs[j].anchor : specs[j].initial;
    anchor(static_cast<Eigen::Index>(j)) = a / specs[j].scale;
  }
  const Eigen::MatrixXd a = std::sqrt(top) * split.null_space * split.d.cwiseInverse().asDiagonal();
  return new ceres::NormalPrior(a, anchor);
}

// The covariance as if the rows were independent (out.naive_*), model units.
void naive_covariance(const std::vector<double>& dense, const std::vector<ParamSpec>& specs,
                      bool scale_free, FitOutcome& out) {
  const std::size_t p = specs.size();
  const auto pp = static_cast<Eigen::Index>(p);
  Eigen::MatrixXd bread = Eigen::MatrixXd::Zero(pp, pp);
  for (std::size_t i = 0; i < out.residuals.size(); ++i) {
    if (!std::isfinite(out.residuals[i])) continue;
    const Eigen::Map<const Eigen::VectorXd> row(dense.data() + i * p, pp);
    bread.noalias() += row * row.transpose();
  }
  const double dof = std::max(1.0, static_cast<double>(out.n) - static_cast<double>(p));
  Eigen::MatrixXd naive = split_information(bread, scale_free).inverse * (out.rss / dof);
  out.naive_sigmas.resize(p);
  out.naive_covariance.resize(p * p);
  for (std::size_t a = 0; a < p; ++a) {
    const auto aa = static_cast<Eigen::Index>(a);
    out.naive_sigmas[a] = std::sqrt(std::max(naive(aa, aa), 0.0)) * specs[a].scale;
    for (std::size_t b = 0; b < p; ++b) {
      out.naive_covariance[a * p + b] =
          naive(aa, static_cast<Eigen::Index>(b)) * specs[a].scale * specs[b].scale;
    }
  }
}

// The sandwich covariance and sigmas (out.covariance, out.sigmas, out.observable), model
// units.
void robust_covariance(const FitProblem& problem, const std::vector<double>& dense,
                       const std::vector<ParamSpec>& specs, bool scale_free, FitOutcome& out) {
  const std::size_t p = specs.size();
  std::vector<std::size_t> groups = problem.row_group;
  if (groups.empty()) groups.assign(problem.row_count, 0);
  const std::vector<double> cov_z = sandwich_covariance(
      dense, p, out.residuals, problem.row_window, groups, problem.window_count, out.observable,
      scale_free, newey_west_lags(problem.window_count), &out.effective_windows, &out.unfixed);
  out.scales.clear();
  for (const ParamSpec& s : specs) out.scales.push_back(s.scale);
  // The same, as if the rows were independent.
  naive_covariance(dense, specs, scale_free, out);
  out.covariance.assign(p * p, 0.0);
  for (std::size_t a = 0; a < p; ++a) {
    for (std::size_t b = 0; b < p; ++b) {
      out.covariance[a * p + b] = cov_z[a * p + b] * specs[a].scale * specs[b].scale;
    }
    out.sigmas[a] =
        out.observable[a] != 0 ? std::sqrt(std::max(out.covariance[a * p + a], 0.0)) : kInf;
  }
}

}  // namespace

FitOutcome fit(const FitProblem& problem, const std::vector<ParamSpec>& specs,
               const FitOptions& options) {
  const std::size_t p = specs.size();
  std::vector<double> z(p);
  for (std::size_t j = 0; j < p; ++j) z[j] = specs[j].initial / specs[j].scale;
  const bool scale_free =
      std::any_of(specs.begin(), specs.end(), [](const ParamSpec& s) { return s.scale_free; });

  auto* cost = new ReplayCost(problem, specs, options.step);
  ceres::Problem solver_problem;
  const ceres::ResidualBlockId replay = solver_problem.AddResidualBlock(cost, nullptr, z.data());
  for (std::size_t j = 0; j < p; ++j) {
    const int jj = static_cast<int>(j);
    if (specs[j].lower > -1e299)
      solver_problem.SetParameterLowerBound(z.data(), jj, specs[j].lower / specs[j].scale);
    if (specs[j].upper < 1e299)
      solver_problem.SetParameterUpperBound(z.data(), jj, specs[j].upper / specs[j].scale);
  }
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options_of(options), &solver_problem, &summary);
  int iterations = static_cast<int>(summary.iterations.size());

  // Jacobian of the replay at the optimum (z units).
  ceres::CRSMatrix jac;
  ceres::Problem::EvaluateOptions eval;
  eval.residual_blocks = {replay};
  bool have_jacobian = solver_problem.Evaluate(eval, nullptr, nullptr, nullptr, &jac);
  std::vector<double> dense;
  const auto theta_of = [&specs, &z, p] {
    std::vector<double> theta(p);
    for (std::size_t j = 0; j < p; ++j) theta[j] = z[j] * specs[j].scale;
    return theta;
  };
  if (have_jacobian) {
    dense = dense_jacobian(jac, p);
    const std::vector<double> optimum = z;
    anchor_uninformed(dense, jac.num_rows, specs, scale_free, z);
    // Along a combination the run hardly fixes the solver can drift far down a flat valley;
    // where the model is not linear in it (ParamSpec::hold_when_unfixed), putting that
    // combination back at its anchors then lands off the valley, worse than the optimum by
    // more than the noise. Solve again from there with it held at its anchors.
    const bool may_hold = std::any_of(specs.begin(), specs.end(),
                                      [](const ParamSpec& s) { return s.hold_when_unfixed; });
    const bool moved = z != optimum;
    const FitOutcome anchored = moved ? score(problem, theta_of()) : FitOutcome{};
    const double optimum_rss = 2.0 * summary.final_cost;  // Ceres' cost is half of it
    const bool off_valley = anchored.ok && anchored.rss > optimum_rss + 1.0;
    if (off_valley && !may_hold && anchored.rss > 2.0 * optimum_rss) {
      // Not a valley at all: at its anchors the fit is off by more than its whole noise, yet
      // the optimum's slope says the combination barely matters (a limit that acts at a few
      // command steps, beside a command delay at its bound). The optimum stands; the
      // combination's sigma stays infinite. (A weakly fixed combination that drifted costs
      // less than that at its anchors and goes back there.)
      z = optimum;
    } else if (off_valley && may_hold) {
      solver_problem.AddResidualBlock(hold_uninformed(dense, jac.num_rows, specs, scale_free),
                                      nullptr, z.data());
      ceres::Solve(solver_options_of(options), &solver_problem, &summary);
      iterations += static_cast<int>(summary.iterations.size());
      have_jacobian = solver_problem.Evaluate(eval, nullptr, nullptr, nullptr, &jac);
      if (have_jacobian) {
        dense = dense_jacobian(jac, p);
        anchor_uninformed(dense, jac.num_rows, specs, scale_free, z);
      }
    }
  }
  FitOutcome out = score(problem, theta_of());
  out.iterations = iterations;
  if (!out.ok || !have_jacobian) return out;
  robust_covariance(problem, dense, specs, scale_free, out);
  return out;
}

}  // namespace swivel::model_gap
