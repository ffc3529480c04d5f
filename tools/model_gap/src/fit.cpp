#include "swivel/model_gap/fit.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace swivel::model_gap {
namespace {

struct Sums {
  double rss_training = 0.0;
  double rss_validation = 0.0;
  std::size_t n_training = 0;
  std::size_t n_validation = 0;
};

Sums sums(const FitProblem& problem, const std::vector<double>& r) {
  Sums s;
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (!std::isfinite(r[i])) continue;
    if (problem.is_training[i]) {
      s.rss_training += r[i] * r[i];
      ++s.n_training;
    } else {
      s.rss_validation += r[i] * r[i];
      ++s.n_validation;
    }
  }
  return s;
}

// Training rows only; rows that are NaN for every parameter value (no motion capture) are
// kept as zeros so that the residual vector keeps a fixed size. Forward differences with a
// fixed step in z: the replay is smooth in its parameters, and a step tied to |z| would
// collapse at z = 0, where every fit starts.
class ReplayCost final : public ceres::CostFunction {
 public:
  ReplayCost(const FitProblem& problem, const std::vector<ParamSpec>& specs, double step)
      : problem_(problem), specs_(specs), step_(step), theta_(specs.size()), z_(specs.size()) {
    for (std::size_t i = 0; i < problem.row_count; ++i) {
      if (problem.is_training[i]) training_rows_.push_back(i);
    }
    set_num_residuals(static_cast<int>(training_rows_.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(specs.size()));
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const std::size_t p = specs_.size();
    for (std::size_t j = 0; j < p; ++j) z_[j] = parameters[0][j];
    if (!evaluate_at(residuals)) return false;
    if (jacobians == nullptr || jacobians[0] == nullptr) return true;
    const std::size_t rows = training_rows_.size();
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

  [[nodiscard]] std::size_t rows() const { return training_rows_.size(); }

 private:
  bool evaluate_at(double* out) const {
    for (std::size_t j = 0; j < specs_.size(); ++j) theta_[j] = z_[j] * specs_[j].scale;
    if (!problem_.residuals(theta_, buffer_)) return false;
    for (std::size_t i = 0; i < training_rows_.size(); ++i) {
      const double r = buffer_[training_rows_[i]];
      out[i] = std::isfinite(r) ? r : 0.0;
    }
    return true;
  }

  const FitProblem& problem_;
  const std::vector<ParamSpec>& specs_;
  double step_;
  std::vector<std::size_t> training_rows_;
  mutable std::vector<double> theta_;
  mutable std::vector<double> z_;
  mutable std::vector<double> buffer_;
  mutable std::vector<double> shifted_;
};

}  // namespace

double bic(double rss, std::size_t n, std::size_t k) {
  if (n == 0) return 0.0;
  const double nn = static_cast<double>(n);
  return nn * std::log(std::max(rss, 1e-300) / nn) + static_cast<double>(k) * std::log(nn);
}

double autocorrelation_inflation(const FitProblem& problem, const std::vector<double>& r) {
  double n = 0.0;
  double n_eff = 0.0;
  std::size_t i = 0;
  while (i < r.size()) {
    const std::size_t g = problem.row_group.empty() ? 0 : problem.row_group[i];
    std::size_t j = i;
    double num = 0.0;
    double den = 0.0;
    double count = 0.0;
    double prev = std::numeric_limits<double>::quiet_NaN();
    while (j < r.size() && (problem.row_group.empty() || problem.row_group[j] == g)) {
      if (problem.is_training[j] && std::isfinite(r[j])) {
        den += r[j] * r[j];
        count += 1.0;
        if (std::isfinite(prev)) num += prev * r[j];
        prev = r[j];
      }
      ++j;
    }
    if (count > 0.0) {
      const double rho = den > 0.0 ? std::clamp(num / den, 0.0, 0.999) : 0.0;
      n += count;
      n_eff += count * (1.0 - rho) / (1.0 + rho);
    }
    i = j;
  }
  return n_eff > 0.0 ? std::sqrt(n / n_eff) : 1.0;
}

FitOutcome score(const FitProblem& problem, std::span<const double> theta) {
  FitOutcome out;
  out.values.assign(theta.begin(), theta.end());
  out.sigmas.assign(theta.size(), 0.0);
  if (!problem.residuals(theta, out.residuals)) return out;
  const Sums s = sums(problem, out.residuals);
  out.ok = true;
  out.rss_training = s.rss_training;
  out.rss_validation = s.rss_validation;
  out.n_training = s.n_training;
  out.n_validation = s.n_validation;
  out.bic = bic(s.rss_training, s.n_training, theta.size());
  return out;
}

FitOutcome fit(const FitProblem& problem, const std::vector<ParamSpec>& specs,
               const FitOptions& options) {
  const std::size_t p = specs.size();
  std::vector<double> z(p);
  for (std::size_t j = 0; j < p; ++j) z[j] = specs[j].initial / specs[j].scale;

  auto* cost = new ReplayCost(problem, specs, options.step);
  ceres::Problem solver_problem;
  solver_problem.AddResidualBlock(cost, nullptr, z.data());
  for (std::size_t j = 0; j < p; ++j) {
    const int jj = static_cast<int>(j);
    if (specs[j].lower > -1e299) solver_problem.SetParameterLowerBound(z.data(), jj, specs[j].lower / specs[j].scale);
    if (specs[j].upper < 1e299) solver_problem.SetParameterUpperBound(z.data(), jj, specs[j].upper / specs[j].scale);
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &solver_problem, &summary);

  std::vector<double> theta(p);
  for (std::size_t j = 0; j < p; ++j) theta[j] = z[j] * specs[j].scale;
  FitOutcome out = score(problem, theta);
  out.iterations = static_cast<int>(summary.iterations.size());
  if (!out.ok) return out;

  // Covariance from the Jacobian at the optimum: s^2 (J^T J)^-1 in z units.
  ceres::CRSMatrix jac;
  ceres::Problem::EvaluateOptions eval;
  if (!solver_problem.Evaluate(eval, nullptr, nullptr, nullptr, &jac)) return out;
  Eigen::MatrixXd j_dense = Eigen::MatrixXd::Zero(jac.num_rows, jac.num_cols);
  for (int r = 0; r < jac.num_rows; ++r) {
    for (int k = jac.rows[static_cast<std::size_t>(r)]; k < jac.rows[static_cast<std::size_t>(r) + 1]; ++k) {
      j_dense(r, jac.cols[static_cast<std::size_t>(k)]) = jac.values[static_cast<std::size_t>(k)];
    }
  }
  const Eigen::MatrixXd info = j_dense.transpose() * j_dense;
  const double dof = std::max<double>(1.0, static_cast<double>(out.n_training) - static_cast<double>(p));
  const double s2 = out.rss_training / dof;
  const double inflation = autocorrelation_inflation(problem, out.residuals);
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(info);
  const bool full_rank = cod.rank() == static_cast<Eigen::Index>(p);
  const Eigen::MatrixXd cov = cod.pseudoInverse() * s2;
  out.covariance.assign(p * p, std::numeric_limits<double>::infinity());
  for (std::size_t j = 0; j < p; ++j) {
    const auto jj = static_cast<Eigen::Index>(j);
    out.sigmas[j] = full_rank ? std::sqrt(std::max(cov(jj, jj), 0.0)) * specs[j].scale * inflation
                              : std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < p && full_rank; ++i) {
      out.covariance[j * p + i] = cov(jj, static_cast<Eigen::Index>(i)) * specs[j].scale *
                                  specs[i].scale * inflation * inflation;
    }
  }
  return out;
}

}  // namespace swivel::model_gap
