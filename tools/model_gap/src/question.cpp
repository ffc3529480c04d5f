// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/question.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "question_stages.hpp"

namespace swivel::model_gap {

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

namespace detail {
namespace {

QuestionReplay with_known_variance(const RobotModel& base, const QuestionReplay& given) {
  QuestionReplay replay = given;
  if (replay.known_variance_of)
    replay.known_variance = replay.known_variance_of(base, initial_nuisance(replay));
  return replay;
}

// The noise of `residuals` (channel units), and the evaluator's weights from it.
void measure_noise(QuestionState& s, const std::vector<double>& residuals) {
  s.noise = estimate_noise(residuals, s.windows, s.replay.noise_x, s.replay.noise_floor,
                           s.replay.known_variance);
  s.eval.set_sigma(row_sigma(s.noise, s.replay));
}

// The nominal model with its nuisance fitted; candidates keep the nuisance there until the
// selection is refitted.
void fit_nominal_nuisance(QuestionState& s, const QuestionOptions& options) {
  const FitOutcome nominal =
      s.replay.nuisance.empty()
          ? score(s.eval.problem({}, false), {})
          : fit(s.eval.problem({}, true), specs_of({}, {}, s.replay.nuisance, s.eval.nuisance()),
                options.fit);
  if (!nominal.ok) throw std::runtime_error("the nominal model cannot be scored");
  s.eval.set_nuisance(nominal.values);
}

// `effects` fitted with the nuisance beside them, started from where the nuisance is now and
// from its initial value; the better fit of the two. The nominal model's nuisance may have
// taken up what the effects explain (a command delay fitted without an acceleration limit
// takes up the limiter's lag, to its one-row bound on a robot limited all run), and a joint
// fit started there stays in that valley with the effect's value off to make up for it.
FitOutcome fit_beside_nuisance(const QuestionState& s, const std::vector<const Candidate*>& effects,
                               const std::vector<double>& values, const QuestionOptions& options) {
  FitOutcome here =
      fit(s.eval.problem(effects, true),
          specs_of(effects, values, s.replay.nuisance, s.eval.nuisance()), options.fit);
  const std::vector<double> nuisance_start = initial_nuisance(s.replay);
  if (nuisance_start == s.eval.nuisance()) return here;
  FitOutcome fresh = fit(s.eval.problem(effects, true),
                         specs_of(effects, values, s.replay.nuisance, nuisance_start), options.fit);
  if (fresh.ok && (!here.ok || fresh.rss < here.rss)) return fresh;
  return here;
}

// The chosen single effect scored with the nuisance refitted beside it (a command timing
// fitted without a lag is not the one with); the nuisance stays there.
void refit_chosen_nuisance(QuestionState& s, const QuestionOptions& options) {
  const Fitted& chosen = *s.chosen;
  const FitOutcome joint = fit_beside_nuisance(s, chosen.effects, chosen.fit.values, options);
  if (!joint.ok) return;
  const auto p = static_cast<std::ptrdiff_t>(param_count(chosen.effects));
  s.eval.set_nuisance(std::vector<double>(joint.values.begin() + p, joint.values.end()));
  Fitted& c = s.singles[static_cast<std::size_t>(s.chosen - s.singles.data())];
  c.fit = score(s.eval.problem(c.effects, false),
                std::vector<double>(joint.values.begin(), joint.values.begin() + p));
  c.fit.sigmas = std::vector<double>(joint.sigmas.begin(), joint.sigmas.begin() + p);
}

// The chosen effect and `other` fitted together, each one's significance and size against
// the other alone.
Fitted fit_pair(const QuestionState& s, const Fitted& chosen, const Fitted& other,
                const QuestionOptions& options) {
  const Candidate* a = chosen.effects[0];
  const Candidate* b = other.effects[0];
  std::vector<double> initial = chosen.fit.values;
  initial.insert(initial.end(), other.fit.values.begin(), other.fit.values.end());
  Fitted p = run_fit(s, {a, b}, initial, options);
  p.z = {added_z(p.fit, 0, a->params.size(), other.fit.rss, a->identity),
         added_z(p.fit, a->params.size(), b->params.size(), chosen.fit.rss, b->identity)};
  p.size = {contribution(p.fit, other.fit, s.windows), contribution(p.fit, chosen.fit, s.windows)};
  p.rss_reference = s.nominal_fixed.rss;
  p.bic_reference = s.nominal_fixed.bic;
  return p;
}

// A second effect, only when the chosen one leaves a pattern behind or another candidate is
// significant on its own (two effects of one channel, such as a gyro bias and a wheel-radius
// difference both turning the heading, can leave no pattern either's misfit tests see): the
// best singles are tried beside it (refitted on the whole run first if they were screened).
void second_effect(QuestionState& s, const std::vector<Candidate>& library,
                   const QuestionOptions& options) {
  if (!s.replay.nuisance.empty()) refit_chosen_nuisance(s, options);
  std::vector<double> raw;
  s.eval.evaluate(s.chosen->effects, s.chosen->fit.values, false, raw, false);
  const std::vector<MisfitTest> left =
      misfit_tests(misfit_inputs(s.replay, raw, s.eval.sigma(), s.residuals_before));
  if (!pattern_left(left, options) && !another_significant(s.singles, s.chosen, options)) return;
  const auto chosen_index = static_cast<std::size_t>(s.chosen - s.singles.data());
  std::size_t tried = 0;
  for (std::size_t k : pair_order(s.singles)) {
    if (tried >= options.pair_pool) break;
    if (k == chosen_index || !s.singles[k].fit.ok) continue;
    ++tried;
    if (s.full[k] == 0) {
      s.singles[k] = single_fit(s, library[k], s.singles[k].fit.values, s.nominal_fixed, options);
      s.full[k] = 1;
    }
    s.pairs.push_back(fit_pair(s, *s.chosen, s.singles[k], options));
  }
  const Fitted* best_pair = choose_pair(s.pairs, *s.chosen, options);
  if (best_pair != nullptr) s.chosen = best_pair;
}

// Every candidate alone, the best (by BIC on the screening stretch) first.
std::vector<std::size_t> screen_order(const std::vector<Fitted>& singles) {
  std::vector<std::size_t> order(singles.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return bic_or_last(singles[a], true) < bic_or_last(singles[b], true);
  });
  return order;
}

// The candidates' scores, best first: by BIC against the nominal model on the same stretch.
std::vector<CandidateScore> candidate_scores(const QuestionState& s) {
  std::vector<CandidateScore> scores;
  for (std::size_t i = 0; i < s.singles.size(); ++i) {
    scores.push_back(score_of(s.singles[i]));
    if (s.full[i] == 0)
      scores.back().label_note = "screened on the first " + std::to_string(s.screen) + " windows";
  }
  for (const Fitted& f : s.pairs) scores.push_back(score_of(f));
  std::sort(scores.begin(), scores.end(), [](const CandidateScore& a, const CandidateScore& b) {
    return a.delta_bic < b.delta_bic;
  });
  return scores;
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

// Per channel, the gap before and after with the final weights `sigma`.
std::vector<ChannelGap> channel_gaps(const QuestionReplay& replay, const std::vector<double>& sigma,
                                     const std::vector<double>& before,
                                     const std::vector<double>& after) {
  const std::size_t w = replay.windows;
  std::vector<ChannelGap> gaps;
  for (std::size_t c = 0; c < replay.channels.size(); ++c) {
    ChannelGap g;
    g.info = replay.channels[c];
    std::vector<double> s(sigma.begin() + static_cast<std::ptrdiff_t>(c * w),
                          sigma.begin() + static_cast<std::ptrdiff_t>((c + 1) * w));
    std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(w / 2), s.end());
    g.noise_sigma = w > 0 ? s[w / 2] : kNaN;
    std::vector<double> wb(w);
    std::vector<double> wa(w);
    for (std::size_t j = 0; j < w; ++j) {
      wb[j] = before[c * w + j] / sigma[c * w + j];
      wa[j] = after[c * w + j] / sigma[c * w + j];
    }
    g.rms_before = rms(before, c * w, w);
    g.rms_after = rms(after, c * w, w);
    g.whitened_rms_before = rms(wb, 0, w);
    g.whitened_rms_after = rms(wa, 0, w);
    gaps.push_back(g);
  }
  return gaps;
}

}  // namespace

QuestionState::QuestionState(const RobotModel& base, const QuestionReplay& given)
    : replay(with_known_variance(base, given)), eval(base, replay), windows(replay.windows) {}

void measure_nominal(QuestionState& s, Question question) {
  s.eval.set_sigma(std::vector<double>(s.replay.channels.size() * s.windows, 1.0));
  if (!s.eval.evaluate({}, {}, false, s.residuals_before, false)) {
    throw std::runtime_error(std::string("the nominal model cannot replay the run (") +
                             question_title(question) + ")");
  }
  measure_noise(s, s.residuals_before);
}

void fit_nominal(QuestionState& s, const QuestionOptions& options) {
  fit_nominal_nuisance(s, options);
  if (s.replay.fit_nuisance_before_noise && !s.replay.nuisance.empty()) {
    // The noise as it is once the nuisance is taken out, and the nuisance again with it.
    if (s.eval.evaluate({}, {}, false, s.residuals_before, false)) {
      measure_noise(s, s.residuals_before);
      fit_nominal_nuisance(s, options);
      s.eval.evaluate({}, {}, false, s.residuals_before, false);
    }
  }
  s.nominal_fixed = score(s.eval.problem({}, false), {});
}

void screen_singles(QuestionState& s, const std::vector<Candidate>& library,
                    const QuestionOptions& options) {
  s.screen = std::max<std::size_t>(
      options.screen_min_windows,
      static_cast<std::size_t>(options.screen_fraction * static_cast<double>(s.windows)));
  s.full.assign(library.size(), 1);
  if (s.screen * 10 >= s.windows * 7) {
    for (const Candidate& c : library)
      s.singles.push_back(single_fit(s, c, {}, s.nominal_fixed, options));
    return;
  }
  s.eval.set_window_limit(s.screen);
  const FitOutcome nominal_screen = score(s.eval.problem({}, false), {});
  for (const Candidate& c : library)
    s.singles.push_back(single_fit(s, c, {}, nominal_screen, options));
  s.eval.set_window_limit(kAllWindows);
  const std::vector<std::size_t> order = screen_order(s.singles);
  std::fill(s.full.begin(), s.full.end(), 0);
  for (std::size_t k = 0; k < order.size() && k < options.refit_count; ++k) {
    const std::size_t i = order[k];
    if (!s.singles[i].fit.ok) continue;
    s.singles[i] = single_fit(s, library[i], s.singles[i].fit.values, s.nominal_fixed, options);
    s.full[i] = 1;
  }
}

void select_effects(QuestionState& s, const std::vector<Candidate>& library,
                    const QuestionOptions& options) {
  s.chosen = choose_single(s.singles, s.full, s.nominal_fixed.bic, options);
  if (s.chosen != nullptr && options.max_effects >= 2) second_effect(s, library, options);
}

namespace {

// The selection refitted, its nuisance started at `nuisance_start`, with the noise its
// residuals show from there; -2 log likelihood of the rows (Gaussian, with that noise) to
// compare it with a start whose noise differs.
struct Refit {
  NoiseModel noise;
  std::vector<double> sigma;
  FitOutcome fit;
  double neg2_log_likelihood = kInf;
};

Refit refit_from(QuestionState& s, const std::vector<const Candidate*>& selected,
                 const std::vector<double>& values, const std::vector<double>& nuisance_start,
                 const QuestionOptions& options) {
  std::vector<double> start = values;
  if (nuisance_start != s.eval.nuisance()) {
    // The effects' values were fitted beside another nuisance: fitted again at this one
    // first, so that the noise is measured where this start is.
    s.eval.set_nuisance(nuisance_start);
    const FitOutcome moved =
        fit(s.eval.problem(selected, false), specs_of(selected, values, {}, {}), options.fit);
    if (moved.ok) start = moved.values;
  }
  if (!selected.empty() && s.replay.known_variance_of) {
    s.replay.known_variance =
        s.replay.known_variance_of(s.eval.model_with(selected, start), nuisance_start);
  }
  std::vector<double> raw;
  if (s.eval.evaluate(selected, start, false, raw, false)) measure_noise(s, raw);
  Refit r;
  r.fit = !selected.empty() || !s.replay.nuisance.empty()
              ? fit(s.eval.problem(selected, true),
                    specs_of(selected, start, s.replay.nuisance, nuisance_start), options.fit)
              : score(s.eval.problem({}, false), {});
  r.noise = s.noise;
  r.sigma = s.eval.sigma();
  if (!r.fit.ok) return r;
  r.neg2_log_likelihood = 0.0;
  for (std::size_t k = 0; k < r.fit.residuals.size() && k < r.sigma.size(); ++k) {
    const double e = r.fit.residuals[k];
    if (std::isfinite(e)) r.neg2_log_likelihood += e * e + 2.0 * std::log(r.sigma[k]);
  }
  return r;
}

}  // namespace

// The selection refitted with the noise it leaves, its nuisance free. Started where the
// nominal model left the nuisance and, with an effect selected, also at the nuisance's initial
// value when that is elsewhere: the nominal model's nuisance may have taken up what the
// effects explain (a command delay fitted without an acceleration limit takes up the
// limiter's lag, to its one-row bound on a robot limited all run), and a fit started there
// stays in that valley, the effect's value off to make up for it and the noise measured to
// suit. Each start with its own noise; the likelier fit is kept.
void refit_selection(QuestionState& s, const QuestionOptions& options) {
  std::vector<const Candidate*> selected;
  std::vector<double> chosen_values;
  if (s.chosen != nullptr) {
    selected = s.chosen->effects;
    chosen_values = s.chosen->fit.values;
  }
  const std::vector<double> here = s.eval.nuisance();
  const std::vector<double> initial = initial_nuisance(s.replay);
  Refit best = refit_from(s, selected, chosen_values, here, options);
  if (!selected.empty() && initial != here) {
    Refit other = refit_from(s, selected, chosen_values, initial, options);
    if (other.neg2_log_likelihood < best.neg2_log_likelihood) {
      best = std::move(other);
    } else {  // the evaluator back where the kept fit started
      s.eval.set_nuisance(here);
      if (s.replay.known_variance_of) {  // selected is not empty here
        s.replay.known_variance =
            s.replay.known_variance_of(s.eval.model_with(selected, chosen_values), here);
      }
    }
  }
  s.noise = best.noise;
  s.eval.set_sigma(best.sigma);
  s.final.effects = selected;
  s.final.fit = std::move(best.fit);
  if (s.chosen != nullptr) {
    s.final.z = s.chosen->z;  // significance as selected
    s.final.size = s.chosen->size;
  }
  s.final.rss_reference = s.nominal_fixed.rss;
  s.final.bic_reference = s.nominal_fixed.bic;
}

void mark_remnant_jumps(const QuestionReplay& replay, const std::vector<double>& before,
                        const std::vector<double>& after, std::vector<MisfitTest>& misfits) {
  const std::size_t w = replay.windows;
  for (MisfitTest& m : misfits) {
    if (m.test != "jumps" || m.jumps.empty()) continue;
    const auto channel = std::find_if(replay.channels.begin(), replay.channels.end(),
                                      [&](const ChannelInfo& c) { return c.name == m.channel; });
    if (channel == replay.channels.end()) continue;
    const auto c = static_cast<std::size_t>(channel - replay.channels.begin());
    m.remnant = std::all_of(m.jumps.begin(), m.jumps.end(), [&](const MisfitTest::Span& span) {
      double left = 0.0;
      double was = 0.0;
      for (std::size_t j = span.first; j < span.first + span.count && j < w; ++j) {
        left += after[c * w + j];
        was += before[c * w + j];
      }
      return std::abs(left) <= kRemnantShare * std::abs(was - left);
    });
  }
}

void measure_misfit(const QuestionState& s, QuestionResult& result) {
  const FitOutcome& refit = s.final.fit;
  const auto effect_params = static_cast<std::ptrdiff_t>(param_count(s.final.effects));
  result.nuisance.assign(refit.values.begin() + effect_params, refit.values.end());
  if (refit.sigmas.size() == refit.values.size()) {
    result.nuisance_sigmas.assign(refit.sigmas.begin() + effect_params, refit.sigmas.end());
  } else {
    result.nuisance_sigmas.assign(result.nuisance.size(), kInf);
  }
  s.eval.evaluate(s.final.effects, refit.values, true, result.residuals_after, false);
  result.misfits = misfit_tests(
      misfit_inputs(s.replay, result.residuals_after, s.eval.sigma(), result.residuals_before));
  if (!s.final.effects.empty())
    mark_remnant_jumps(s.replay, result.residuals_before, result.residuals_after, result.misfits);
  result.channels =
      channel_gaps(s.replay, s.eval.sigma(), result.residuals_before, result.residuals_after);
  for (std::size_t c = 0; c < result.channels.size(); ++c) {
    if (c < s.noise.a.size()) result.channels[c].rest_sigma = std::sqrt(s.noise.a[c]);
    if (c < s.replay.stated_variance.size() && s.replay.stated_variance[c] > 0.0)
      result.channels[c].stated_sigma = std::sqrt(s.replay.stated_variance[c]);
  }
}

void attribute_gap(QuestionState& s, const QuestionOptions& options, QuestionResult& result) {
  if (s.chosen != nullptr) return;
  const MisfitTest* gap = counting_misfit(result.misfits, options);
  if (gap == nullptr) return;
  const Fitted* best = choose_attribution(s.singles, s.full, s.nominal_fixed.bic, *gap, options);
  if (best == nullptr) return;
  const MisfitTest detected = *gap;
  // What refit_selection changes, to put back if the candidate leaves a gap.
  const NoiseModel noise = s.noise;
  const std::vector<double> sigma = s.eval.sigma();
  const std::vector<double> nuisance = s.eval.nuisance();
  const std::vector<double> known_variance = s.replay.known_variance;
  Fitted nominal = s.final;
  s.chosen = best;
  refit_selection(s, options);
  QuestionResult with;
  with.residuals_before = result.residuals_before;
  measure_misfit(s, with);
  if (s.final.fit.ok && counting_misfit(with.misfits, options) == nullptr) {
    result.nuisance = std::move(with.nuisance);
    result.nuisance_sigmas = std::move(with.nuisance_sigmas);
    result.residuals_after = std::move(with.residuals_after);
    result.misfits = std::move(with.misfits);
    result.channels = std::move(with.channels);
    result.attributed_gap = {detected};
    return;
  }
  s.chosen = nullptr;
  s.noise = noise;
  s.eval.set_sigma(sigma);
  s.eval.set_nuisance(nuisance);
  s.replay.known_variance = known_variance;
  s.final = std::move(nominal);
}

std::vector<NoiseFinding> stated_noise_findings(const QuestionReplay& replay,
                                                const NoiseModel& noise, double min_ratio) {
  std::vector<NoiseFinding> findings;
  for (std::size_t c = 0; c < replay.stated_variance.size() && c < noise.a.size(); ++c) {
    const double stated = replay.stated_variance[c];
    if (!(stated > 0.0)) continue;
    const double ratio = std::sqrt(noise.a[c] / stated);
    if (!(ratio >= min_ratio)) continue;
    findings.push_back({replay.channels[c], std::sqrt(noise.a[c]), std::sqrt(stated), ratio,
                        c < replay.stated_source.size() ? replay.stated_source[c] : ""});
  }
  std::sort(findings.begin(), findings.end(),
            [](const NoiseFinding& x, const NoiseFinding& y) { return x.ratio > y.ratio; });
  return findings;
}

}  // namespace detail

QuestionResult analyse_question(Question question, const RobotModel& base,
                                const QuestionReplay& given, const std::vector<Candidate>& library,
                                const QuestionOptions& options) {
  detail::QuestionState s(base, given);
  const auto wall_start = std::chrono::steady_clock::now();
  QuestionResult result;
  result.question = question;
  result.augmented = base;
  detail::measure_nominal(s, question);
  detail::fit_nominal(s, options);
  detail::screen_singles(s, library, options);
  detail::select_effects(s, library, options);
  detail::refit_selection(s, options);
  result.residuals_before = s.residuals_before;
  result.candidates = detail::candidate_scores(s);
  detail::measure_misfit(s, result);
  detail::attribute_gap(s, options, result);
  result.noise_findings = detail::stated_noise_findings(s.replay, s.noise, options.min_noise_ratio);
  const detail::VerdictInputs verdict{question,
                                      &base,
                                      &s.singles,
                                      s.chosen,
                                      &s.final,
                                      &s.full,
                                      s.nominal_fixed.bic,
                                      &s.nominal_fixed,
                                      &s.replay.window_start_s};
  detail::give_verdict(verdict, options, result);
  detail::calibrate_own_parameters(verdict, options, result);
  if (!result.noise_findings.empty()) {
    const NoiseFinding& f = result.noise_findings.front();
    std::ostringstream line;
    line << " Noise larger than the model states: " << f.channel.name << " " << std::setprecision(2)
         << std::fixed << f.ratio << "x (" << f.source << ")";
    if (result.noise_findings.size() > 1)
      line << " and " << result.noise_findings.size() - 1 << " more channel(s)";
    line << "; effects smaller than that noise stay hidden.";
    result.summary += line.str();
  }
  result.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace swivel::model_gap
