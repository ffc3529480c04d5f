// SPDX-License-Identifier: Apache-2.0
// The question's verdict (question_stages.hpp): unexplained residual when a misfit test
// fires, no significant gap when nothing was selected, else the selection named (on its own
// significance, or as what takes away a gap the misfit tests detected).
#include <Eigen/Core>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numeric>
#include <optional>
#include <sstream>
#include <vector>

#include "question_stages.hpp"

namespace swivel::model_gap::detail {
namespace {

std::string fmt(double v, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

std::string percent(double share) { return std::to_string(std::lround(100.0 * share)) + " %"; }

std::string one_decimal(double v) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << v;
  return s.str();
}

// Where `f` takes the gap against `nominal` (question.hpp, Undecided::where_s): per window
// the drop of the whitened sum of squares over channels.
void locate_gain(const Fitted& f, const FitOutcome& nominal, const std::vector<double>& start_s,
                 Undecided& u) {
  const std::size_t windows = start_s.size();
  if (windows == 0 || f.fit.residuals.size() != nominal.residuals.size()) return;
  std::vector<double> gain(windows, 0.0);
  for (std::size_t i = 0; i < nominal.residuals.size(); ++i) {
    const double before = nominal.residuals[i];
    const double after = f.fit.residuals[i];
    if (std::isfinite(before) && std::isfinite(after))
      gain[i % windows] += before * before - after * after;
  }
  std::vector<std::size_t> order(windows);
  std::iota(order.begin(), order.end(), 0);
  std::ranges::sort(order, [&gain](std::size_t a, std::size_t b) { return gain[a] > gain[b]; });
  double total = 0.0;
  for (double g : gain) total += std::max(g, 0.0);
  double top = 0.0;
  std::vector<std::size_t> where;
  for (std::size_t k = 0; k < std::min(kUndecidedWhere, windows) && gain[order[k]] > 0.0; ++k) {
    where.push_back(order[k]);
    top += gain[order[k]];
  }
  std::ranges::sort(where);
  for (std::size_t j : where) u.where_s.push_back(start_s[j]);
  u.where_share = total > 0.0 ? top / total : 0.0;
}

// The best single candidate by BIC, fitted on every window, when it takes most of the gap
// and would be named but for the few windows it rests on: as on many windows (its statistic
// against the normal, its sigmas unwidened) it passes every condition of significant()
// (question.hpp, Undecided).
std::optional<Undecided> undecided_of(const VerdictInputs& in, const QuestionOptions& options) {
  const std::vector<std::size_t> order = singles_by_bic(*in.singles, in.full, kInf);
  if (order.empty()) return std::nullopt;
  const Fitted& f = (*in.singles)[order.front()];
  if (f.basis.empty() || significant(f, options)) return std::nullopt;
  Fitted on_many = f;
  on_many.z = {f.basis[0].z_many};
  for (double& sigma : on_many.fit.sigmas) sigma /= std::sqrt(f.basis[0].widening);
  const CandidateScore s = score_of(f);
  if (!(s.explained > kUndecidedShare) || !significant(on_many, options)) return std::nullopt;
  Undecided u{s, f.basis[0].windows, f.basis[0].widening, f.basis[0].z_many, {}, 0.0};
  const FitOutcome* beside = nominal_beside_of(f);
  const FitOutcome* nominal = beside != nullptr ? beside : in.nominal;
  if (nominal != nullptr && in.window_start_s != nullptr)
    locate_gain(f, *nominal, *in.window_start_s, u);
  return u;
}

// "the run leans towards steering_lag (steering_lag.time_constant_s = 0.057 +- 0.012): ...".
std::string undecided_sentence(const Undecided& u, const QuestionOptions& options) {
  const CandidateScore& c = u.candidate;
  std::string values;
  for (std::size_t k = 0; k < c.param_names.size(); ++k) {
    values += (values.empty() ? "" : ", ") + c.param_names[k] + " = " + fmt(c.values[k], 4) +
              " +- " + fmt(c.sigmas[k], 2);
  }
  const double z = c.z.empty() ? 0.0 : c.z[0];
  std::string where;
  for (double t : u.where_s) where += (where.empty() ? "" : ", ") + one_decimal(t);
  if (!where.empty()) {
    where = ", " + percent(u.where_share) + " of it in the windows from " + where + " s";
  }
  return "the run leans towards " + c.label() + " (" + values + "): it takes " +
         percent(c.explained) + " of what the nominal model leaves" + where + ", and would be " +
         fmt(u.z_many, 2) + " sigma on many windows, but it rests on about " + fmt(u.windows, 2) +
         " (its variance widened " + fmt(u.widening, 3) +
         " times by the residuals' correlation), and on so few it is " + fmt(z, 2) +
         " sigma, below " + fmt(options.min_z_name, 2) +
         ". A run with more of the motion it acts in would decide.";
}

std::string unexplained_summary(const VerdictInputs& in, const QuestionOptions& options,
                                const MisfitTest& m, const std::string& title,
                                const std::optional<Undecided>& undecided) {
  std::string best = "none";
  if (in.chosen != nullptr)
    best = score_of(*in.final).label() + " (named nothing: it leaves this behind)";
  std::string summary = "Unexplained residual (" + title + "): " + m.channel + " " + m.label +
                        " (" + fmt(m.z, 3) + " sigma, " + fmt(m.size, 2) +
                        " noise sigmas) after the best library candidate " + best + ".";
  if (undecided) summary += " Undecided: " + undecided_sentence(*undecided, options);
  return summary;
}

// Why a fit was not named, in words: significant()'s first failed condition ("below 5 sigma",
// "an RMS change of 0.2 noise sigmas, below 0.5", ...), or why a significant one was not
// selected.
std::string not_named_because(const Fitted& f, const QuestionOptions& options) {
  const Shortfall s = shortfall(f, options);
  switch (s.kind) {
    case Shortfall::Kind::kFitFailed: return "its fit failed";
    case Shortfall::Kind::kBelowSignificance:
      return "below " + fmt(options.min_z_name, 2) + " sigma";
    case Shortfall::Kind::kTooSmall:
      return "an RMS change of " + fmt(f.size[s.effect], 2) + " noise sigmas, below " +
             fmt(options.min_effect_size, 2);
    case Shortfall::Kind::kUnresolved: return "within what the replay resolves";
    case Shortfall::Kind::kNone: break;
  }
  return "not selected (screened out on the run's first stretch, or no lower BIC than the "
         "model's)";
}

std::string no_gap_summary(const VerdictInputs& in, const QuestionOptions& options,
                           const std::string& title, const std::optional<Undecided>& undecided) {
  if (undecided) {
    return "No significant gap (" + title +
           "), but undecided: " + undecided_sentence(*undecided, options);
  }
  const Fitted* best = nullptr;
  for (const Fitted& f : *in.singles) {
    if (!f.fit.ok || f.z.empty()) continue;
    if (best == nullptr || f.z[0] > best->z[0]) best = &f;
  }
  std::string why = "no candidate could be fitted";
  if (best != nullptr) {
    why = "most significant candidate " + best->effects[0]->name + " at " + fmt(best->z[0], 2) +
          " sigma: " + not_named_because(*best, options);
  }
  return "No significant gap (" + title + "): the model agrees with the run to within its noise (" +
         why + ").";
}

// The effect's parameters [first, first + m) of `fit`: its covariance (m x m) projected off
// the combinations the run leaves open with more than kUnfixedShare in this effect (in a
// pair, one nearly all the other effect leaves this one fixed), which then count as not
// observable.
void drop_open_combinations(const FitOutcome& fit, std::size_t first, std::size_t m,
                            std::vector<double>& covariance) {
  const auto mm = static_cast<Eigen::Index>(m);
  Eigen::MatrixXd open(mm, 0);
  for (const std::vector<double>& u : fit.unfixed) {
    if (u.size() < first + m || fit.scales.size() < first + m) continue;
    Eigen::VectorXd part(mm);
    double share = 0.0;  // u has unit length in scaled units
    for (std::size_t k = 0; k < m; ++k) {
      part(static_cast<Eigen::Index>(k)) = u[first + k] * fit.scales[first + k];
      share += u[first + k] * u[first + k];
    }
    if (!(share > kUnfixedShare)) continue;
    open.conservativeResize(mm, open.cols() + 1);
    open.col(open.cols() - 1) = part;
  }
  if (open.cols() == 0) return;
  // Orthonormal basis of the open part, then Q = I - B B'.
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(open, Eigen::ComputeThinU);
  const double top = svd.singularValues().maxCoeff();
  Eigen::MatrixXd q = Eigen::MatrixXd::Identity(mm, mm);
  for (Eigen::Index k = 0; k < svd.singularValues().size(); ++k) {
    if (!(svd.singularValues()(k) > 1e-9 * top)) continue;
    q -= svd.matrixU().col(k) * svd.matrixU().col(k).transpose();
  }
  const Eigen::Map<const Eigen::MatrixXd> c(covariance.data(), mm, mm);
  const Eigen::MatrixXd projected = q * c * q;
  for (Eigen::Index a = 0; a < mm; ++a) {
    for (Eigen::Index b = 0; b < mm; ++b) {
      covariance[static_cast<std::size_t>(a * mm + b)] = projected(a, b);
    }
  }
}

}  // namespace

FittedEffect fitted_effect(const Fitted& final, const CandidateScore& s, std::size_t e,
                           std::size_t first) {
  const Candidate& c = *final.effects[e];
  FittedEffect fe;
  fe.name = c.name;
  fe.limits = c.target == Candidate::Target::kLimits;
  fe.keys = c.keys;
  fe.z = e < final.z.size() ? final.z[e] : 0.0;
  fe.inverse = c.inverse;
  fe.identity = c.identity;
  const std::size_t m = c.params.size();
  const std::size_t p = final.fit.values.size();
  fe.fit_covariance.assign(m * m, 0.0);
  std::size_t i = first;
  for (std::size_t k = 0; k < m; ++k, ++i) {
    fe.values.push_back(s.values[i]);
    fe.sigmas.push_back(s.sigmas[i]);
    fe.fit_values.push_back(final.fit.values[i]);
    for (std::size_t l = 0; l < m; ++l) {
      fe.fit_covariance[k * m + l] =
          final.fit.covariance.empty() ? 0.0 : final.fit.covariance[(first + k) * p + first + l];
    }
    const double res = c.fit_resolution(k, final.fit.values[i]);
    fe.fit_covariance[k * m + k] += res * res;
  }
  drop_open_combinations(final.fit, first, m, fe.fit_covariance);
  for (std::size_t k = 0; k < m; ++k) {
    const double partial = std::sqrt(std::max(fe.fit_covariance[k * m + k], 0.0));
    fe.partial_sigmas.push_back(c.inverse[k] != 0 ? c.sigma(k, final.fit.values[first + k], partial)
                                                  : partial);
  }
  std::vector<double> zero(m, 0.0);
  (void)mahalanobis_squared(zero, fe.fit_covariance, fe.observable_combinations);
  return fe;
}

namespace {

// Whether a misfit test is significant and as large as the noise: what makes a residual
// unexplained, unless it is the selection's remnant.
bool past_misfit_bar(const MisfitTest& m, const QuestionOptions& options) {
  return m.z >= options.min_z_misfit && m.size >= options.min_misfit_size;
}

// The summary of a named selection `s` whose effects are in result.named.
std::string named_summary(const CandidateScore& s, const QuestionResult& result,
                          const QuestionOptions& options, const std::string& title) {
  std::string zs;
  for (const FittedEffect& fe : result.named) zs += (zs.empty() ? "" : ", ") + fmt(fe.z, 3);
  std::string sizes;
  for (double v : s.size) sizes += (sizes.empty() ? "" : ", ") + fmt(v, 3);
  std::string why = "significant at " + zs + " sigma";
  if (!result.attributed_gap.empty()) {
    const MisfitTest& m = result.attributed_gap.front();
    why = "the gap the misfit tests found without it (" + m.channel + " " + m.label + ", " +
          fmt(m.z, 3) + " sigma) is gone with it, the best candidate at " + zs + " sigma";
  }
  std::string summary = "Named " + s.label() + " (" + title + "): " + why + ", an RMS change of " +
                        sizes + " noise sigmas; what remains shows no pattern";
  const auto remnant =
      std::find_if(result.misfits.begin(), result.misfits.end(),
                   [&](const MisfitTest& m) { return m.remnant && past_misfit_bar(m, options); });
  if (remnant != result.misfits.end()) {
    summary += " but where it acts: " + remnant->channel + " keeps " + remnant->label + " (" +
               fmt(remnant->size, 2) +
               " noise sigmas), each less than half the change it brings there (its form is "
               "approximate)";
  }
  return summary + ".";
}

// Single candidates other than the chosen one, fitted on every window and significant on
// their own, whose BIC lies within kRivalBic of the chosen one's; best first.
std::vector<CandidateScore> rivals_of(const VerdictInputs& in, const QuestionOptions& options) {
  std::vector<CandidateScore> out;
  if (in.chosen == nullptr || in.chosen->effects.size() != 1) return out;
  for (std::size_t k : singles_by_bic(*in.singles, in.full, in.chosen->fit.bic + kRivalBic)) {
    const Fitted& f = (*in.singles)[k];
    if (&f != in.chosen && significant(f, options)) out.push_back(score_of(f));
  }
  return out;
}

// "The run barely tells it from X (BIC 2.2 higher, itself significant at 8.7 sigma)...".
std::string rivals_sentence(const std::vector<CandidateScore>& rivals, double chosen_bic) {
  if (rivals.empty()) return "";
  std::string list;
  for (const CandidateScore& r : rivals) {
    list += (list.empty() ? "" : "; ") + r.label() + " (BIC " + fmt(r.bic - chosen_bic, 2) +
            " higher, itself significant at " + fmt(r.z.empty() ? 0.0 : r.z[0], 3) + " sigma)";
  }
  return " The run barely tells it from " + list +
         ": a run that moves in more ways, or what you know of the robot, decides.";
}

void name_selection(const VerdictInputs& in, const QuestionOptions& options,
                    const std::string& title, QuestionResult& result) {
  const Fitted& final = *in.final;
  const CandidateScore s = score_of(final);
  std::size_t first = 0;
  for (std::size_t e = 0; e < final.effects.size(); ++e) {
    result.named.push_back(fitted_effect(final, s, e, first));
    first += final.effects[e]->params.size();
  }
  result.augmented = model_with(*in.base, final.effects, final.fit.values);
  result.summary = named_summary(s, result, options, title);
  result.rivals = rivals_of(in, options);
  if (in.chosen != nullptr) result.summary += rivals_sentence(result.rivals, in.chosen->fit.bic);
}

}  // namespace

const MisfitTest* counting_misfit(const std::vector<MisfitTest>& misfits,
                                  const QuestionOptions& options) {
  const auto counts = [&](const MisfitTest& m) {
    return !m.remnant && past_misfit_bar(m, options);
  };
  const auto first = std::find_if(misfits.begin(), misfits.end(), counts);
  return first != misfits.end() ? &*first : nullptr;
}

void give_verdict(const VerdictInputs& in, const QuestionOptions& options, QuestionResult& result) {
  const std::string title = question_title(in.question);
  if (in.chosen == nullptr) result.undecided = undecided_of(in, options);
  if (const MisfitTest* m = counting_misfit(result.misfits, options); m != nullptr) {
    result.verdict = Verdict::kUnexplained;
    result.summary = unexplained_summary(in, options, *m, title, result.undecided);
  } else if (in.chosen == nullptr) {
    result.verdict = Verdict::kNoSignificantGap;
    result.summary = no_gap_summary(in, options, title, result.undecided);
  } else {
    result.verdict = Verdict::kNamed;
    name_selection(in, options, title, result);
  }
}

}  // namespace swivel::model_gap::detail
