// SPDX-License-Identifier: Apache-2.0
// Selection of the question's effects by forward steps (question_stages.hpp): the best
// significant single effect, then a second one only if it is significant in the pair.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "question_stages.hpp"

namespace swivel::model_gap::detail {
namespace {

// Whether effect e of a fit is further from the model's own values than the replay can
// resolve (a limit, a latency), at significance `min_z`.
bool resolved(const Fitted& f, std::size_t e, double min_z) {
  std::size_t first = 0;
  for (std::size_t k = 0; k < e; ++k) first += f.effects[k]->params.size();
  const Candidate& c = *f.effects[e];
  if (!c.named_only_when_resolved) return true;
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
  return count == 0.0 || chi_square_z(chi2, count) >= min_z;
}

}  // namespace

std::vector<std::size_t> singles_by_bic(const std::vector<Fitted>& singles,
                                        const std::vector<char>* full, double below) {
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < singles.size(); ++k) {
    if (full != nullptr && (*full)[k] == 0) continue;
    if (singles[k].fit.ok && singles[k].fit.bic < below) order.push_back(k);
  }
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return singles[a].fit.bic < singles[b].fit.bic; });
  return order;
}

Shortfall shortfall(const Fitted& f, const QuestionOptions& options) {
  if (!f.fit.ok) return {Shortfall::Kind::kFitFailed, 0};
  for (std::size_t e = 0; e < f.z.size(); ++e) {
    if (f.z[e] < options.min_z_name) return {Shortfall::Kind::kBelowSignificance, e};
    if (f.size[e] < options.min_effect_size) return {Shortfall::Kind::kTooSmall, e};
    if (!resolved(f, e, options.min_z_name)) return {Shortfall::Kind::kUnresolved, e};
  }
  return {};
}

bool significant(const Fitted& f, const QuestionOptions& options) {
  return shortfall(f, options).kind == Shortfall::Kind::kNone;
}

const Fitted* choose_single(const std::vector<Fitted>& singles, const std::vector<char>& full,
                            double nominal_bic, const QuestionOptions& options) {
  for (std::size_t k : singles_by_bic(singles, &full, nominal_bic)) {
    if (significant(singles[k], options)) return &singles[k];
  }
  return nullptr;
}

const Fitted* choose_attribution(const std::vector<Fitted>& singles, const std::vector<char>& full,
                                 double nominal_bic, const MisfitTest& gap,
                                 const QuestionOptions& options) {
  const std::vector<std::size_t> order = singles_by_bic(singles, &full, nominal_bic);
  if (order.empty()) return nullptr;
  const Fitted& best = singles[order.front()];
  // k parameters can take away k isolated jumps whatever made them (one steering offset per
  // caster, one slip event per window): only fewer parameters than jumps say which effect.
  const bool fewer_than_jumps = gap.test != "jumps" || param_count(best.effects) < gap.jumps.size();
  const bool attributable = best.z.size() == 1 && best.z[0] >= options.min_z_attribute &&
                            best.size[0] >= options.min_effect_size &&
                            resolved(best, 0, options.min_z_attribute) && fewer_than_jumps;
  return attributable ? &best : nullptr;
}

bool pattern_left(const std::vector<MisfitTest>& left, const QuestionOptions& options) {
  return std::any_of(left.begin(), left.end(), [&](const MisfitTest& m) {
    return m.test != "jumps" && m.z >= options.min_z_name && m.size >= options.min_effect_size;
  });
}

bool another_significant(const std::vector<Fitted>& singles, const Fitted* chosen,
                         const QuestionOptions& options) {
  return std::any_of(singles.begin(), singles.end(),
                     [&](const Fitted& f) { return &f != chosen && significant(f, options); });
}

std::vector<std::size_t> pair_order(const std::vector<Fitted>& singles) {
  std::vector<std::size_t> pool(singles.size());
  std::iota(pool.begin(), pool.end(), 0U);
  std::sort(pool.begin(), pool.end(), [&](std::size_t a, std::size_t b) {
    return (singles[a].fit.ok ? singles[a].fit.bic - singles[a].bic_reference : kInf) <
           (singles[b].fit.ok ? singles[b].fit.bic - singles[b].bic_reference : kInf);
  });
  return pool;
}

const Fitted* choose_pair(const std::vector<Fitted>& pairs, const Fitted& chosen,
                          const QuestionOptions& options) {
  const Fitted* best_pair = nullptr;
  for (const Fitted& p : pairs) {
    if (!significant(p, options) || p.fit.bic >= chosen.fit.bic) continue;
    if (best_pair == nullptr || p.fit.bic < best_pair->fit.bic) best_pair = &p;
  }
  return best_pair;
}

}  // namespace swivel::model_gap::detail
