// SPDX-License-Identifier: Apache-2.0
// The fitting toolkit the question's stages share (question_stages.hpp): the residual
// function of a set of effects, fits of candidates, and what a fit is worth.
#include <algorithm>
#include <cmath>

#include "question_stages.hpp"

namespace swivel::model_gap::detail {

RobotModel model_with(const RobotModel& base, const std::vector<const Candidate*>& effects,
                      std::span<const double> theta) {
  RobotModel m = base;
  std::size_t i = 0;
  for (const Candidate* e : effects) {
    e->apply(m, theta.subspan(i, e->params.size()));
    i += e->params.size();
  }
  return m;
}

Evaluator::Evaluator(const RobotModel& base, const QuestionReplay& replay)
    : base_(base), replay_(replay) {
  for (const ParamSpec& p : replay.nuisance) nuisance_.push_back(p.initial);
}

FitProblem Evaluator::problem(const std::vector<const Candidate*>& effects,
                              bool fit_nuisance) const {
  FitProblem p;
  const std::size_t w = replay_.windows;
  p.row_count = replay_.channels.size() * w;
  p.window_count = w;
  p.row_window.resize(p.row_count);
  p.row_group.resize(p.row_count);
  for (std::size_t i = 0; i < p.row_count; ++i) {
    p.row_window[i] = i % w;
    p.row_group[i] = i / w;
  }
  p.residuals = [this, effects, fit_nuisance](std::span<const double> theta,
                                              std::vector<double>& r) {
    return evaluate(effects, theta, fit_nuisance, r, true);
  };
  return p;
}

bool Evaluator::evaluate(const std::vector<const Candidate*>& effects,
                         std::span<const double> theta, bool fit_nuisance, std::vector<double>& r,
                         bool whiten) const {
  model_ = base_;
  std::size_t i = 0;
  for (const Candidate* e : effects) {
    e->apply(model_, theta.subspan(i, e->params.size()));
    i += e->params.size();
  }
  const std::span<const double> nuisance =
      fit_nuisance ? theta.subspan(i) : std::span<const double>(nuisance_);
  if (!replay_.residuals(model_, nuisance, raw_, limit_)) return false;
  r.resize(raw_.size());
  for (std::size_t k = 0; k < raw_.size(); ++k) r[k] = whiten ? raw_[k] / sigma_[k] : raw_[k];
  return true;
}

// A correlated run can make a change of a tenth of the noise statistically significant; it
// is still not worth a name.
double contribution(const FitOutcome& with, const FitOutcome& without, std::size_t windows) {
  if (!with.ok || !without.ok || with.residuals.size() != without.residuals.size() || windows == 0)
    return 0.0;
  const std::size_t channels = with.residuals.size() / windows;
  double largest = 0.0;
  for (std::size_t c = 0; c < channels; ++c) {
    double s = 0.0;
    double n = 0.0;
    for (std::size_t j = 0; j < windows; ++j) {
      const double d = without.residuals[c * windows + j] - with.residuals[c * windows + j];
      if (!std::isfinite(d)) continue;
      s += d * d;
      n += 1.0;
    }
    if (n > 0.0) largest = std::max(largest, std::sqrt(s / n));
  }
  return largest;
}

std::vector<ParamSpec> specs_of(const std::vector<const Candidate*>& effects,
                                const std::vector<double>& initial,
                                const std::vector<ParamSpec>& nuisance,
                                const std::vector<double>& nuisance_initial) {
  std::vector<ParamSpec> specs;
  std::size_t i = 0;
  for (const Candidate* e : effects) {
    for (ParamSpec p : e->params) {
      if (i < initial.size()) p.initial = initial[i];
      specs.push_back(p);
      ++i;
    }
  }
  for (std::size_t k = 0; k < nuisance.size(); ++k) {
    ParamSpec p = nuisance[k];
    if (k < nuisance_initial.size()) p.initial = nuisance_initial[k];
    specs.push_back(p);
  }
  return specs;
}

// The drop of the residual sum of squares the effect brings as a likelihood-ratio
// statistic, divided by how much the residuals' correlation widens its parameters'
// uncertainty. A likelihood ratio, not a Wald test against the nominal values: a limit the
// run barely reaches is precisely fitted yet changes nothing, and must not count as
// significant.
double added_z(const FitOutcome& with, std::size_t first, std::size_t count, double rss_without,
               const std::vector<double>& identity, SignificanceBasis* basis) {
  if (!with.ok || with.n <= with.values.size() || with.covariance.empty() ||
      with.naive_covariance.empty()) {
    return 0.0;
  }
  const std::size_t p = with.values.size();
  std::vector<double> d(count);
  std::vector<double> sandwich(count * count);
  std::vector<double> naive(count * count);
  for (std::size_t a = 0; a < count; ++a) {
    d[a] = with.values[first + a] - identity[a];
    for (std::size_t b = 0; b < count; ++b) {
      sandwich[a * count + b] = with.covariance[(first + a) * p + first + b];
      naive[a * count + b] = with.naive_covariance[(first + a) * p + first + b];
    }
  }
  // How much the residuals' correlation widens the uncertainty along the fitted change.
  std::size_t rank = 0;
  std::size_t naive_rank = 0;
  const double w_sandwich = mahalanobis_squared(d, sandwich, rank);
  const double w_naive = mahalanobis_squared(d, naive, naive_rank);
  if (rank == 0 || !(w_sandwich > 0.0) || !std::isfinite(w_naive)) return 0.0;
  const double inflation = std::max(1.0, w_naive / w_sandwich);
  const double s2 = with.rss / static_cast<double>(with.n - p);
  if (!(s2 > 0.0)) return 0.0;
  const double lr = std::max(0.0, rss_without - with.rss) / s2;
  // Against F on what the variance was estimated from. Where the sandwich widens it, that is
  // the windows the effect's parameters rest on: an acceleration limit is informed by a
  // handful of command steps, and its z must not be that of a hundred windows. Otherwise the
  // rows' own variance, from every row.
  const bool widened = inflation > 1.0;
  const double dof = widened ? fewest_windows(with.effective_windows, first, count)
                             : static_cast<double>(with.n - p);
  if (basis != nullptr) {
    basis->windows = widened ? dof : 0.0;
    basis->widening = inflation;
    basis->z_many = chi_square_z(lr / inflation, static_cast<double>(rank));
  }
  return wald_f_z(lr / inflation, static_cast<double>(rank), dof);
}

CandidateScore score_of(const Fitted& f) {
  const double rss0 = f.rss_reference;
  const double bic0 = f.bic_reference;
  CandidateScore s;
  s.ok = f.fit.ok;
  s.z = f.z;
  s.size = f.size;
  s.iterations = f.fit.iterations;
  std::size_t i = 0;
  for (const Candidate* e : f.effects) {
    s.effects.push_back(e->name);
    for (std::size_t k = 0; k < e->params.size(); ++k, ++i) {
      s.param_names.push_back(e->params[k].name);
      const double v = i < f.fit.values.size() ? f.fit.values[i] : kNaN;
      double sg = kInf;  // not fitted: unknown
      if (i < f.fit.sigmas.size()) sg = f.fit.sigmas[i];
      s.values.push_back(e->value(k, v));
      s.sigmas.push_back(e->sigma(k, v, sg));
    }
  }
  if (f.fit.ok) {
    s.bic = f.fit.bic;
    s.delta_bic = f.fit.bic - bic0;
    s.explained = rss0 > 0.0 ? (rss0 - f.fit.rss) / rss0 : 0.0;
  } else {
    s.bic = kInf;
    s.delta_bic = kInf;
  }
  return s;
}

std::vector<double> row_sigma(const NoiseModel& noise, const QuestionReplay& replay) {
  const std::size_t w = replay.windows;
  std::vector<double> sigma(replay.channels.size() * w);
  for (std::size_t c = 0; c < replay.channels.size(); ++c) {
    for (std::size_t j = 0; j < w; ++j) {
      const double known = replay.known_variance.empty() ? 0.0 : replay.known_variance[c * w + j];
      sigma[c * w + j] = noise.sigma(c, replay.noise_x[c][j], std::isfinite(known) ? known : 0.0);
    }
  }
  return sigma;
}

// BIC is counted on the effects' parameters alone, as the nominal model's has its nuisance
// fitted too.
FitOutcome effects_part(FitOutcome joint, std::size_t p) {
  const std::size_t all = joint.values.size();
  if (!joint.ok || all <= p) return joint;
  const auto keep = [p](std::vector<double>& v) { v.resize(std::min(v.size(), p)); };
  const auto block = [p, all](std::vector<double>& m) {
    if (m.size() != all * all) return;
    std::vector<double> out(p * p);
    for (std::size_t a = 0; a < p; ++a) {
      for (std::size_t b = 0; b < p; ++b) out[a * p + b] = m[a * all + b];
    }
    m = std::move(out);
  };
  // A combination not fixed that is mostly nuisance leaves the effects fixed; one with a
  // sizeable part in the effects (a common steering offset against the motion capture's yaw
  // offset) leaves that part open, whatever the nuisance was put back to.
  std::vector<std::vector<double>> open;
  for (std::vector<double>& u : joint.unfixed) {
    if (u.size() != all) continue;
    double share = 0.0;
    for (std::size_t a = 0; a < p; ++a) share += u[a] * u[a];
    if (share > kUnfixedShare)
      open.emplace_back(u.begin(), u.begin() + static_cast<std::ptrdiff_t>(p));
  }
  joint.unfixed = std::move(open);
  keep(joint.scales);
  keep(joint.values);
  keep(joint.sigmas);
  keep(joint.naive_sigmas);
  joint.observable.resize(std::min(joint.observable.size(), p));
  block(joint.covariance);
  block(joint.naive_covariance);
  joint.bic = bic(joint.rss, joint.n, p);
  return joint;
}

std::size_t param_count(const std::vector<const Candidate*>& effects) {
  std::size_t p = 0;
  for (const Candidate* e : effects) p += e->params.size();
  return p;
}

MisfitInputs misfit_inputs(const QuestionReplay& replay, const std::vector<double>& residuals,
                           const std::vector<double>& sigma,
                           const std::vector<double>& residuals_before) {
  MisfitInputs m;
  m.channels = replay.channels;
  m.windows = replay.windows;
  m.residuals = residuals;
  m.sigma = sigma;
  // The regressor is the base model's predicted change: the measured one carries the
  // motion capture's noise, which the residual shares, and would correlate with it by itself.
  m.own_change.resize(residuals.size());
  for (std::size_t k = 0; k < residuals.size(); ++k)
    m.own_change[k] = replay.own_change[k] - residuals_before[k];
  m.accel = replay.accel;
  m.start_yaw_rad = replay.start_yaw_rad;
  m.wheel_sin_change = replay.wheel_sin_change;
  m.wheel_cos_change = replay.wheel_cos_change;
  m.slowest_roll_offsets = replay.slowest_roll_offsets;
  return m;
}

std::vector<double> initial_nuisance(const QuestionReplay& replay) {
  std::vector<double> initial;
  for (const ParamSpec& p : replay.nuisance) initial.push_back(p.initial);
  return initial;
}

namespace {

// Whether a nuisance parameter sits on (within a thousandth of its range of) a bound.
bool nuisance_at_bound(const std::vector<ParamSpec>& specs, const std::vector<double>& values) {
  for (std::size_t k = 0; k < std::min(specs.size(), values.size()); ++k) {
    const ParamSpec& p = specs[k];
    const double margin = 1e-3 * (p.upper - p.lower);
    if (values[k] <= p.lower + margin || values[k] >= p.upper - margin) return true;
  }
  return false;
}

}  // namespace

Fitted run_fit(const QuestionState& s, std::vector<const Candidate*> effects,
               const std::vector<double>& initial, const QuestionOptions& options) {
  Fitted f;
  f.effects = std::move(effects);
  if (s.replay.refit_nuisance_with_candidates && !s.replay.nuisance.empty()) {
    std::vector<double> start = initial;
    start.resize(std::min(start.size(), param_count(f.effects)));
    f.fit = effects_part(
        fit(s.eval.problem(f.effects, true),
            specs_of(f.effects, start, s.replay.nuisance, s.eval.nuisance()), options.fit),
        param_count(f.effects));
  } else {
    f.fit =
        fit(s.eval.problem(f.effects, false), specs_of(f.effects, initial, {}, {}), options.fit);
    if (nuisance_at_bound(s.replay.nuisance, s.eval.nuisance())) {
      // The nominal model pushed its nuisance to a bound: it is taking up something else
      // (a command delay, the lag of a limiter the model lacks), and the effect fitted
      // beside it would make up for the rest. The effect fitted at the nuisance's initial
      // value instead, when that fits better.
      Evaluator at_initial = s.eval;
      at_initial.set_nuisance(initial_nuisance(s.replay));
      const FitOutcome other = fit(at_initial.problem(f.effects, false),
                                   specs_of(f.effects, initial, {}, {}), options.fit);
      if (other.ok && (!f.fit.ok || other.rss < f.fit.rss)) {
        f.fit = other;
        f.nominal_beside = score(at_initial.problem({}, false), {});
      }
    }
  }
  return f;
}

const FitOutcome* nominal_beside_of(const Fitted& f) {
  return f.nominal_beside.has_value() && f.nominal_beside->ok ? &*f.nominal_beside : nullptr;
}

Fitted single_fit(const QuestionState& s, const Candidate& c, const std::vector<double>& initial,
                  const FitOutcome& reference, const QuestionOptions& options) {
  Fitted f = run_fit(s, {&c}, initial, options);
  f.basis.resize(1);
  f.z = {added_z(f.fit, 0, c.params.size(), reference.rss, c.identity, f.basis.data())};
  // Against the nominal model at the same nuisance: where the nominal model's command delay
  // ran to its bound standing in for a lag, the lag fitted without it changes the replay by
  // what the delay had taken up.
  const FitOutcome* beside = nominal_beside_of(f);
  f.size = {contribution(f.fit, beside != nullptr ? *beside : reference, s.windows)};
  f.rss_reference = reference.rss;
  f.bic_reference = reference.bic;
  return f;
}

}  // namespace swivel::model_gap::detail
