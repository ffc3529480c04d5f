// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/question.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace swivel::model_gap {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(double v, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

// The residual function of a set of effects on the question's base model: whitened rows,
// the effects' parameters first, then the nuisance parameters when they are fitted (else
// their fixed values).
class Evaluator {
 public:
  Evaluator(const RobotModel& base, const QuestionReplay& replay) : base_(base), replay_(replay) {
    for (const ParamSpec& p : replay.nuisance) nuisance_.push_back(p.initial);
  }

  void set_sigma(std::vector<double> sigma) { sigma_ = std::move(sigma); }
  [[nodiscard]] const std::vector<double>& sigma() const { return sigma_; }
  /// Windows replayed (the rest read NaN): a shorter stretch for screening.
  void set_window_limit(std::size_t limit) { limit_ = limit; }
  /// Values of the nuisance parameters when a fit leaves them out.
  void set_nuisance(std::vector<double> values) { nuisance_ = std::move(values); }
  [[nodiscard]] const std::vector<double>& nuisance() const { return nuisance_; }

  [[nodiscard]] FitProblem problem(const std::vector<const Candidate*>& effects,
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

  // Residuals in channel units (whiten = false) or whitened.
  bool evaluate(const std::vector<const Candidate*>& effects, std::span<const double> theta,
                bool fit_nuisance, std::vector<double>& r, bool whiten) const {
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

  [[nodiscard]] RobotModel model_with(const std::vector<const Candidate*>& effects,
                                      std::span<const double> theta) const {
    RobotModel m = base_;
    std::size_t i = 0;
    for (const Candidate* e : effects) {
      e->apply(m, theta.subspan(i, e->params.size()));
      i += e->params.size();
    }
    return m;
  }

 private:
  const RobotModel& base_;
  const QuestionReplay& replay_;
  std::vector<double> sigma_;
  std::vector<double> nuisance_;
  std::size_t limit_ = static_cast<std::size_t>(-1);
  mutable RobotModel model_;
  mutable std::vector<double> raw_;
};

struct Fitted {
  std::vector<const Candidate*> effects;
  FitOutcome fit;
  std::vector<double> z;     // per effect: significance
  std::vector<double> size;  // per effect: what it changes (contribution())
  // The nominal model on the same stretch (screening fits a shorter one).
  double rss_reference = 0.0;
  double bic_reference = 0.0;
};

// How much an effect changes the prediction: the largest, over channels, RMS of the
// whitened residuals' change it brings (noise sigmas). A correlated run can make a change of
// a tenth of the noise statistically significant; it is still not worth a name.
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

// The effects' parameter specs (from `initial` where given), then the nuisance ones.
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

// Significance of one effect in a fit: the drop of the residual sum of squares it brings
// (against the same fit without it, `rss_without`) as a likelihood-ratio statistic, divided
// by how much the residuals' correlation widens its parameters' uncertainty. A likelihood
// ratio, not a Wald test against the nominal values: a limit the run barely reaches is
// precisely fitted yet changes nothing, and must not count as significant.
double added_z(const FitOutcome& with, std::size_t first, std::size_t count, double rss_without,
               const std::vector<double>& identity) {
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
  return chi_square_z(lr / inflation, static_cast<double>(rank));
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
      const double sg = i < f.fit.sigmas.size() ? f.fit.sigmas[i] : kInf;
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

double rms(const std::vector<double>& v, std::size_t first, std::size_t count) {
  double s = 0.0;
  double n = 0.0;
  for (std::size_t k = first; k < first + count; ++k) {
    if (!std::isfinite(v[k])) continue;
    s += v[k] * v[k];
    n += 1.0;
  }
  return n > 0.0 ? std::sqrt(s / n) : kNaN;
}

}  // namespace

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::kNoSignificantGap: return "no significant gap";
    case Verdict::kNamed: return "named";
    case Verdict::kUnexplained: return "unexplained residual";
  }
  return "unknown";
}

std::string CandidateScore::label() const {
  std::string s;
  for (const auto& e : effects) s += (s.empty() ? "" : " + ") + e;
  return s.empty() ? "nominal" : s;
}

namespace {

// The effects' part (the first p parameters) of a fit that had the nuisance free beside
// them: their values, sigmas and covariance; BIC counted on the effects' parameters alone, as
// the nominal model's has its nuisance fitted too.
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
  return m;
}

}  // namespace

QuestionResult analyse_question(Question question, const RobotModel& base,
                                const QuestionReplay& given, const std::vector<Candidate>& library,
                                const QuestionOptions& options) {
  QuestionReplay replay = given;
  std::vector<double> nuisance_initial;
  for (const ParamSpec& p : replay.nuisance) nuisance_initial.push_back(p.initial);
  if (replay.known_variance_of)
    replay.known_variance = replay.known_variance_of(base, nuisance_initial);
  const auto wall_start = std::chrono::steady_clock::now();
  QuestionResult result;
  result.question = question;
  result.augmented = base;
  const std::size_t w = replay.windows;
  const std::size_t channels = replay.channels.size();

  // 1. The nominal residual and the noise it shows.
  Evaluator eval(base, replay);
  eval.set_sigma(std::vector<double>(channels * w, 1.0));
  if (!eval.evaluate({}, {}, false, result.residuals_before, false)) {
    throw std::runtime_error(std::string("the nominal model cannot replay the run (") +
                             question_title(question) + ")");
  }
  NoiseModel noise = estimate_noise(result.residuals_before, w, replay.noise_x, replay.noise_floor,
                                    replay.known_variance);
  eval.set_sigma(row_sigma(noise, replay));

  // 2. The nominal model with its nuisance fitted; candidates keep the nuisance there until
  //    the selection is refitted.
  const auto fit_nominal = [&]() {
    Fitted f;
    f.fit = replay.nuisance.empty()
                ? score(eval.problem({}, false), {})
                : fit(eval.problem({}, true), specs_of({}, {}, replay.nuisance, eval.nuisance()),
                      options.fit);
    return f;
  };
  Fitted nominal = fit_nominal();
  if (!nominal.fit.ok) throw std::runtime_error("the nominal model cannot be scored");
  eval.set_nuisance(nominal.fit.values);
  if (replay.fit_nuisance_before_noise && !replay.nuisance.empty()) {
    // The noise as it is once the nuisance is taken out, and the nuisance again with it.
    if (eval.evaluate({}, {}, false, result.residuals_before, false)) {
      noise = estimate_noise(result.residuals_before, w, replay.noise_x, replay.noise_floor,
                             replay.known_variance);
      eval.set_sigma(row_sigma(noise, replay));
      nominal = fit_nominal();
      if (!nominal.fit.ok) throw std::runtime_error("the nominal model cannot be scored");
      eval.set_nuisance(nominal.fit.values);
      eval.evaluate({}, {}, false, result.residuals_before, false);
    }
  }
  const auto run_fit = [&](std::vector<const Candidate*> effects,
                           const std::vector<double>& initial) {
    Fitted f;
    f.effects = std::move(effects);
    if (replay.refit_nuisance_with_candidates && !replay.nuisance.empty()) {
      std::vector<double> start = initial;
      start.resize(std::min(start.size(), param_count(f.effects)));
      f.fit = effects_part(
          fit(eval.problem(f.effects, true),
              specs_of(f.effects, start, replay.nuisance, eval.nuisance()), options.fit),
          param_count(f.effects));
    } else {
      f.fit =
          fit(eval.problem(f.effects, false), specs_of(f.effects, initial, {}, {}), options.fit);
    }
    return f;
  };
  const auto single_fit = [&](const Candidate& c, const std::vector<double>& initial,
                              double rss_nominal, const FitOutcome& nominal_fit) {
    Fitted f = run_fit({&c}, initial);
    f.z = {added_z(f.fit, 0, c.params.size(), rss_nominal, c.identity)};
    f.size = {contribution(f.fit, nominal_fit, w)};
    f.rss_reference = nominal_fit.rss;
    f.bic_reference = nominal_fit.bic;
    return f;
  };
  const FitOutcome nominal_fixed = score(eval.problem({}, false), {});

  // 3. Every candidate alone. A long run is screened: every candidate is fitted on its first
  //    stretch, and the most promising ones again on the whole run.
  const std::size_t screen = std::max<std::size_t>(
      options.screen_min_windows,
      static_cast<std::size_t>(options.screen_fraction * static_cast<double>(w)));
  const bool screening = screen * 10 < w * 7;
  std::vector<Fitted> singles;
  std::vector<char> full(library.size(), 1);
  if (screening) {
    eval.set_window_limit(screen);
    const FitOutcome nominal_screen = score(eval.problem({}, false), {});
    for (const Candidate& c : library)
      singles.push_back(single_fit(c, {}, nominal_screen.rss, nominal_screen));
    eval.set_window_limit(static_cast<std::size_t>(-1));
    std::vector<std::size_t> order(singles.size());
    std::iota(order.begin(), order.end(), 0U);
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      const double ba = singles[a].fit.ok ? singles[a].fit.bic : kInf;
      const double bb = singles[b].fit.ok ? singles[b].fit.bic : kInf;
      return ba < bb;
    });
    std::fill(full.begin(), full.end(), 0);
    for (std::size_t k = 0; k < order.size() && k < options.refit_count; ++k) {
      const std::size_t i = order[k];
      if (!singles[i].fit.ok) continue;
      singles[i] = single_fit(library[i], singles[i].fit.values, nominal_fixed.rss, nominal_fixed);
      full[i] = 1;
    }
  } else {
    for (const Candidate& c : library)
      singles.push_back(single_fit(c, {}, nominal_fixed.rss, nominal_fixed));
  }
  // An effect is named when significant, large enough to matter, and further from the
  // model's own values than the replay can resolve (a lag, a limit).
  const auto resolved = [&](const Fitted& f, std::size_t e) {
    std::size_t first = 0;
    for (std::size_t k = 0; k < e; ++k) first += f.effects[k]->params.size();
    const Candidate& c = *f.effects[e];
    double chi2 = 0.0;
    double count = 0.0;
    for (std::size_t i = 0; i < c.params.size(); ++i) {
      const double value = f.fit.values[first + i];
      const double resolution = c.fit_resolution(i, value);
      if (resolution <= 0.0) continue;
      const double sigma = std::hypot(
          std::isfinite(f.fit.sigmas[first + i]) ? f.fit.sigmas[first + i] : 0.0, resolution);
      chi2 += std::pow((value - c.identity[i]) / sigma, 2);
      count += 1.0;
    }
    return count == 0.0 || chi_square_z(chi2, count) >= options.min_z_name;
  };
  const auto significant = [&](const Fitted& f) {
    if (!f.fit.ok) return false;
    for (std::size_t e = 0; e < f.z.size(); ++e) {
      if (f.z[e] < options.min_z_name || f.size[e] < options.min_effect_size || !resolved(f, e))
        return false;
    }
    return true;
  };
  std::vector<std::size_t> order(singles.size());
  std::iota(order.begin(), order.end(), 0U);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const double ba = singles[a].fit.ok && full[a] ? singles[a].fit.bic : kInf;
    const double bb = singles[b].fit.ok && full[b] ? singles[b].fit.bic : kInf;
    return ba < bb;
  });
  const Fitted* chosen = nullptr;
  for (std::size_t k : order) {
    if (full[k] && significant(singles[k]) && singles[k].fit.bic < nominal_fixed.bic) {
      chosen = &singles[k];
      break;
    }
  }

  // 4. A second effect, only when the chosen one leaves a pattern behind (judged with the
  //    nuisance refitted beside it: a command timing fitted without a lag is not the one with).
  std::vector<Fitted> pairs;
  if (chosen != nullptr && options.max_effects >= 2) {
    if (!replay.nuisance.empty()) {
      const FitOutcome joint =
          fit(eval.problem(chosen->effects, true),
              specs_of(chosen->effects, chosen->fit.values, replay.nuisance, eval.nuisance()),
              options.fit);
      if (joint.ok) {
        const std::size_t p = param_count(chosen->effects);
        eval.set_nuisance(std::vector<double>(joint.values.begin() + static_cast<std::ptrdiff_t>(p),
                                              joint.values.end()));
        Fitted& c = singles[static_cast<std::size_t>(chosen - singles.data())];
        c.fit = score(eval.problem(c.effects, false),
                      std::vector<double>(joint.values.begin(),
                                          joint.values.begin() + static_cast<std::ptrdiff_t>(p)));
        c.fit.sigmas = std::vector<double>(joint.sigmas.begin(),
                                           joint.sigmas.begin() + static_cast<std::ptrdiff_t>(p));
      }
    }
    std::vector<double> raw;
    eval.evaluate(chosen->effects, chosen->fit.values, false, raw, false);
    const std::vector<MisfitTest> left =
        misfit_tests(misfit_inputs(replay, raw, eval.sigma(), result.residuals_before));
    const bool pattern_left = std::any_of(left.begin(), left.end(), [&](const MisfitTest& m) {
      return m.test != "jumps" && m.z >= options.min_z_name && m.size >= options.min_effect_size;
    });
    if (pattern_left) {
      const std::size_t chosen_index = static_cast<std::size_t>(chosen - singles.data());
      std::size_t tried = 0;
      // Best singles by BIC on the stretch they were fitted on.
      std::vector<std::size_t> pool(singles.size());
      std::iota(pool.begin(), pool.end(), 0U);
      std::sort(pool.begin(), pool.end(), [&](std::size_t a, std::size_t b) {
        return (singles[a].fit.ok ? singles[a].fit.bic - singles[a].bic_reference : kInf) <
               (singles[b].fit.ok ? singles[b].fit.bic - singles[b].bic_reference : kInf);
      });
      for (std::size_t k : pool) {
        if (tried >= options.pair_pool) break;
        if (k == chosen_index || !singles[k].fit.ok) continue;
        ++tried;
        if (!full[k]) {
          singles[k] =
              single_fit(library[k], singles[k].fit.values, nominal_fixed.rss, nominal_fixed);
          full[k] = 1;
        }
        const Fitted& other = singles[k];
        const Candidate* a = chosen->effects[0];
        const Candidate* b = other.effects[0];
        std::vector<double> initial = chosen->fit.values;
        initial.insert(initial.end(), other.fit.values.begin(), other.fit.values.end());
        Fitted p = run_fit({a, b}, initial);
        p.z = {added_z(p.fit, 0, a->params.size(), other.fit.rss, a->identity),
               added_z(p.fit, a->params.size(), b->params.size(), chosen->fit.rss, b->identity)};
        p.size = {contribution(p.fit, other.fit, w), contribution(p.fit, chosen->fit, w)};
        p.rss_reference = nominal_fixed.rss;
        p.bic_reference = nominal_fixed.bic;
        pairs.push_back(std::move(p));
      }
      const Fitted* best_pair = nullptr;
      for (const Fitted& p : pairs) {
        if (!significant(p) || p.fit.bic >= chosen->fit.bic) continue;
        if (best_pair == nullptr || p.fit.bic < best_pair->fit.bic) best_pair = &p;
      }
      if (best_pair != nullptr) chosen = best_pair;
    }
  }

  // 5. With the selection known, the noise is measured on what it leaves, and the selection
  //    refitted with those weights and its nuisance free: its values and uncertainties are
  //    the reported ones.
  std::vector<const Candidate*> selected;
  if (chosen != nullptr) selected = chosen->effects;
  Fitted final;
  {
    std::vector<double> raw;
    const std::vector<double> chosen_values =
        chosen != nullptr ? chosen->fit.values : std::vector<double>{};
    if (replay.known_variance_of && chosen != nullptr) {
      replay.known_variance =
          replay.known_variance_of(eval.model_with(selected, chosen_values), eval.nuisance());
    }
    if (eval.evaluate(selected, chosen_values, false, raw, false)) {
      noise = estimate_noise(raw, w, replay.noise_x, replay.noise_floor, replay.known_variance);
      eval.set_sigma(row_sigma(noise, replay));
    }
    const std::vector<double> initial =
        chosen != nullptr ? chosen->fit.values : std::vector<double>{};
    final.effects = selected;
    if (!selected.empty() || !replay.nuisance.empty()) {
      final.fit = fit(eval.problem(selected, true),
                      specs_of(selected, initial, replay.nuisance, eval.nuisance()), options.fit);
    } else {
      final.fit = score(eval.problem({}, false), {});
    }
    if (chosen != nullptr) {
      final.z = chosen->z;  // significance as selected
      final.size = chosen->size;
    }
    final.rss_reference = nominal_fixed.rss;
    final.bic_reference = nominal_fixed.bic;
  }

  for (std::size_t i = 0; i < singles.size(); ++i) {
    result.candidates.push_back(score_of(singles[i]));
    if (!full[i])
      result.candidates.back().label_note =
          "screened on the first " + std::to_string(screen) + " windows";
  }
  for (const Fitted& f : pairs) result.candidates.push_back(score_of(f));
  // Best first: by BIC against the nominal model on the same stretch.
  std::sort(
      result.candidates.begin(), result.candidates.end(),
      [](const CandidateScore& a, const CandidateScore& b) { return a.delta_bic < b.delta_bic; });

  // 6. What remains, and the tests for what the library does not hold.
  const std::size_t effect_params = param_count(selected);
  result.nuisance.assign(final.fit.values.begin() + static_cast<std::ptrdiff_t>(effect_params),
                         final.fit.values.end());
  if (final.fit.sigmas.size() == final.fit.values.size()) {
    result.nuisance_sigmas.assign(
        final.fit.sigmas.begin() + static_cast<std::ptrdiff_t>(effect_params),
        final.fit.sigmas.end());
  } else {
    result.nuisance_sigmas.assign(result.nuisance.size(), kInf);
  }
  eval.evaluate(selected, final.fit.values, true, result.residuals_after, false);
  result.misfits = misfit_tests(
      misfit_inputs(replay, result.residuals_after, eval.sigma(), result.residuals_before));
  const auto counts = [&](const MisfitTest& m) {
    return m.z >= options.min_z_misfit && m.size >= options.min_misfit_size;
  };
  const auto first_misfit = std::find_if(result.misfits.begin(), result.misfits.end(), counts);
  const bool misfit_found = first_misfit != result.misfits.end();

  // Per channel, before and after.
  for (std::size_t c = 0; c < channels; ++c) {
    ChannelGap g;
    g.info = replay.channels[c];
    std::vector<double> s(eval.sigma().begin() + static_cast<std::ptrdiff_t>(c * w),
                          eval.sigma().begin() + static_cast<std::ptrdiff_t>((c + 1) * w));
    std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(w / 2), s.end());
    g.noise_sigma = w > 0 ? s[w / 2] : kNaN;
    std::vector<double> wb(w);
    std::vector<double> wa(w);
    for (std::size_t j = 0; j < w; ++j) {
      wb[j] = result.residuals_before[c * w + j] / eval.sigma()[c * w + j];
      wa[j] = result.residuals_after[c * w + j] / eval.sigma()[c * w + j];
    }
    g.rms_before = rms(result.residuals_before, c * w, w);
    g.rms_after = rms(result.residuals_after, c * w, w);
    g.whitened_rms_before = rms(wb, 0, w);
    g.whitened_rms_after = rms(wa, 0, w);
    result.channels.push_back(g);
  }

  // 7. The verdict.
  const std::string title = question_title(question);
  if (misfit_found) {
    const MisfitTest& m = *first_misfit;
    result.verdict = Verdict::kUnexplained;
    std::string best = "none";
    if (chosen != nullptr)
      best = score_of(final).label() + " (named nothing: it leaves this behind)";
    result.summary = "Unexplained residual (" + title + "): " + m.channel + " " + m.label + " (" +
                     fmt(m.z, 3) + " sigma, " + fmt(m.size, 2) +
                     " noise sigmas) after the best library candidate " + best + ".";
  } else if (chosen == nullptr) {
    result.verdict = Verdict::kNoSignificantGap;
    double best_z = 0.0;
    std::string best = "none";
    for (std::size_t i = 0; i < singles.size(); ++i) {
      const Fitted& f = singles[i];
      if (!f.fit.ok || f.z.empty()) continue;
      if (f.z[0] > best_z) {
        best_z = f.z[0];
        best = f.effects[0]->name;
      }
    }
    result.summary = "No significant gap (" + title +
                     "): the model agrees with the run to within its noise "
                     "(most significant candidate " +
                     best + " at " + fmt(best_z, 2) + " sigma, below " +
                     fmt(options.min_z_name, 2) + ", or too small to matter).";
  } else {
    result.verdict = Verdict::kNamed;
    const CandidateScore s = score_of(final);
    std::size_t i = 0;
    for (std::size_t e = 0; e < selected.size(); ++e) {
      const Candidate& c = *selected[e];
      FittedEffect fe;
      fe.name = c.name;
      fe.limits = c.target == Candidate::Target::kLimits;
      fe.keys = c.keys;
      fe.z = e < final.z.size() ? final.z[e] : 0.0;
      fe.inverse = c.inverse;
      const std::size_t first = i;
      const std::size_t m = c.params.size();
      const std::size_t p = final.fit.values.size();
      fe.fit_covariance.assign(m * m, 0.0);
      for (std::size_t k = 0; k < m; ++k, ++i) {
        fe.values.push_back(s.values[i]);
        fe.sigmas.push_back(s.sigmas[i]);
        fe.fit_values.push_back(final.fit.values[i]);
        for (std::size_t l = 0; l < m; ++l) {
          fe.fit_covariance[k * m + l] = final.fit.covariance.empty()
                                             ? 0.0
                                             : final.fit.covariance[(first + k) * p + first + l];
        }
        const double res = c.fit_resolution(k, final.fit.values[i]);
        fe.fit_covariance[k * m + k] += res * res;
        const double partial = std::sqrt(std::max(fe.fit_covariance[k * m + k], 0.0));
        fe.partial_sigmas.push_back(c.inverse[k] ? c.sigma(k, final.fit.values[i], partial)
                                                 : partial);
      }
      std::vector<double> zero(m, 0.0);
      (void)mahalanobis_squared(zero, fe.fit_covariance, fe.observable_combinations);
      result.named.push_back(fe);
    }
    result.augmented = eval.model_with(selected, final.fit.values);
    std::string zs;
    for (const FittedEffect& fe : result.named) zs += (zs.empty() ? "" : ", ") + fmt(fe.z, 3);
    std::string sizes;
    for (double v : s.size) sizes += (sizes.empty() ? "" : ", ") + fmt(v, 3);
    result.summary = "Named " + s.label() + " (" + title + "): significant at " + zs +
                     " sigma, an RMS change of " + sizes +
                     " noise sigmas; what remains shows no pattern.";
  }
  result.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace swivel::model_gap
