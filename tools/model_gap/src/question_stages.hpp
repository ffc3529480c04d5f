// SPDX-License-Identifier: Apache-2.0
#pragma once
// The stages of analyse_question (question.hpp), each a function of its own:
//   nominal      the nominal residual, the noise it shows, the nominal fit with its nuisance;
//   screen       every candidate alone (a long run first on a shorter stretch);
//   select       the best significant single effect, then a second one if it earns its place;
//   refit        the selection again with the noise it leaves and its nuisance free;
//   misfit       what remains, and the tests for what the library does not hold;
//   attribute    a gap those tests detect with nothing selected, put down to the best
//                candidate when that takes it away;
//   noise        the noise the fit took against what the model's sensor figures state;
//   verdict      no significant gap, named, or unexplained residual, and its summary;
//   calibrate    with nothing named, the robot model's own parameters the run fixes.
// What the stages share is QuestionState, passed from one to the next. Internal to the
// model-gap library: the public interface is question.hpp.

#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "swivel/model_gap/fit.hpp"
#include "swivel/model_gap/library.hpp"
#include "swivel/model_gap/misfit.hpp"
#include "swivel/model_gap/noise_model.hpp"
#include "swivel/model_gap/question.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::model_gap::detail {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// A combination not fixed leaves an effect's part of it open when that part is more than
/// this share of it (of its squared length in scaled units), as fit() judges a parameter.
inline constexpr double kUnfixedShare = 0.01;
/// Every window of the run (Evaluator::set_window_limit).
inline constexpr std::size_t kAllWindows = static_cast<std::size_t>(-1);

/// `base` with `effects` applied, their fit-unit values one after the other in `theta`.
RobotModel model_with(const RobotModel& base, const std::vector<const Candidate*>& effects,
                      std::span<const double> theta);

/// The residual function of a set of effects on the question's base model: whitened rows,
/// the effects' parameters first, then the nuisance parameters when they are fitted (else
/// their fixed values).
class Evaluator {
 public:
  Evaluator(const RobotModel& base, const QuestionReplay& replay);

  void set_sigma(std::vector<double> sigma) { sigma_ = std::move(sigma); }
  [[nodiscard]] const std::vector<double>& sigma() const { return sigma_; }
  /// Windows replayed (the rest read NaN): a shorter stretch for screening.
  void set_window_limit(std::size_t limit) { limit_ = limit; }
  /// Values of the nuisance parameters when a fit leaves them out.
  void set_nuisance(std::vector<double> values) { nuisance_ = std::move(values); }
  [[nodiscard]] const std::vector<double>& nuisance() const { return nuisance_; }

  [[nodiscard]] FitProblem problem(const std::vector<const Candidate*>& effects,
                                   bool fit_nuisance) const;
  /// Residuals in channel units (whiten = false) or whitened.
  bool evaluate(const std::vector<const Candidate*>& effects, std::span<const double> theta,
                bool fit_nuisance, std::vector<double>& r, bool whiten) const;
  [[nodiscard]] RobotModel model_with(const std::vector<const Candidate*>& effects,
                                      std::span<const double> theta) const {
    return detail::model_with(base_, effects, theta);
  }

 private:
  const RobotModel& base_;
  const QuestionReplay& replay_;
  std::vector<double> sigma_;
  std::vector<double> nuisance_;
  std::size_t limit_ = kAllWindows;
  mutable RobotModel model_;
  mutable std::vector<double> raw_;
};

/// What an effect's significance rests on, where the residuals' correlation widened it: the
/// windows its parameters' variance comes from (the F test's second degree of freedom) and
/// how much that correlation widened their uncertainty along the fitted change.
struct SignificanceBasis {
  double windows = 0.0;  ///< 0: not widened; the rows' own variance, from every row
  double widening = 1.0;
  double z_many = 0.0;  ///< the same statistic against the normal (as if on many windows)
};

/// One candidate (a single effect or a pair) as fitted.
struct Fitted {
  std::vector<const Candidate*> effects;
  FitOutcome fit;
  std::vector<double> z;                 ///< per effect: significance
  std::vector<SignificanceBasis> basis;  ///< per effect, where known (single candidates)
  std::vector<double> size;              ///< per effect: what it changes (contribution())
  /// The nominal model at the nuisance this fit was made beside, where that is not the
  /// question's (run_fit()); what the effect changes is measured against it.
  std::optional<FitOutcome> nominal_beside;
  /// The nominal model on the same stretch (screening fits a shorter one).
  double rss_reference = 0.0;
  double bic_reference = 0.0;
};

/// The fit's BIC when it succeeded and `usable` (else infinite: last when sorting by BIC).
inline double bic_or_last(const Fitted& f, bool usable) {
  if (usable && f.fit.ok) return f.fit.bic;
  return kInf;
}

/// What the stages share, from the nominal residual to the refitted selection.
struct QuestionState {
  QuestionState(const RobotModel& base, const QuestionReplay& given);
  QuestionState(const QuestionState&) = delete;
  QuestionState& operator=(const QuestionState&) = delete;
  ~QuestionState() = default;

  QuestionReplay replay;  ///< the given one, with its known variance measured
  Evaluator eval;         ///< on `base` and `replay`
  std::size_t windows = 0;
  NoiseModel noise;
  std::vector<double> residuals_before;  ///< channel-major, channel units
  FitOutcome nominal_fixed;              ///< the nominal model, nuisance fixed, every window
  std::vector<Fitted> singles;           ///< per library candidate
  std::vector<char> full;                ///< per library candidate: fitted on every window
  std::size_t screen = 0;                ///< windows of the screening stretch
  std::vector<Fitted> pairs;
  const Fitted* chosen = nullptr;  ///< in singles or pairs; none: nothing selected
  Fitted final;                    ///< the selection refitted (the nominal model if none)
};

// --- Fitting toolkit (question_fit.cpp) ---

/// How much an effect changes the prediction: the largest, over channels, RMS of the
/// whitened residuals' change it brings (noise sigmas).
double contribution(const FitOutcome& with, const FitOutcome& without, std::size_t windows);
/// The effects' parameter specs (from `initial` where given), then the nuisance ones.
std::vector<ParamSpec> specs_of(const std::vector<const Candidate*>& effects,
                                const std::vector<double>& initial,
                                const std::vector<ParamSpec>& nuisance,
                                const std::vector<double>& nuisance_initial);
/// Significance of the `count` parameters from `first` in a fit, against the same fit
/// without them (`rss_without`), as a normal deviate; what it rests on in `basis` when given.
double added_z(const FitOutcome& with, std::size_t first, std::size_t count, double rss_without,
               const std::vector<double>& identity, SignificanceBasis* basis = nullptr);
/// The effects' part (the first p parameters) of a fit that had the nuisance free beside them;
/// of the combinations it left open, those more than kUnfixedShare in the effects.
FitOutcome effects_part(FitOutcome joint, std::size_t p);
std::size_t param_count(const std::vector<const Candidate*>& effects);
CandidateScore score_of(const Fitted& f);
/// The nominal model a single was fitted beside where that is not the question's
/// (Fitted::nominal_beside, when it could be scored); else nullptr.
const FitOutcome* nominal_beside_of(const Fitted& f);
/// Per row (channel-major), the noise sigma of the replay's windows.
std::vector<double> row_sigma(const NoiseModel& noise, const QuestionReplay& replay);
MisfitInputs misfit_inputs(const QuestionReplay& replay, const std::vector<double>& residuals,
                           const std::vector<double>& sigma,
                           const std::vector<double>& residuals_before);
/// The nuisance parameters' initial values (a command delay of zero, no motion-capture offset).
std::vector<double> initial_nuisance(const QuestionReplay& replay);
/// `effects` fitted from `initial` (the nuisance beside them when the replay asks for it).
Fitted run_fit(const QuestionState& s, std::vector<const Candidate*> effects,
               const std::vector<double>& initial, const QuestionOptions& options);
/// One candidate fitted, with its significance and size against `reference` (the nominal
/// model on the same stretch).
Fitted single_fit(const QuestionState& s, const Candidate& c, const std::vector<double>& initial,
                  const FitOutcome& reference, const QuestionOptions& options);

// --- Selection (selection.cpp) ---

/// Whether every effect of a fit is significant, large enough to matter, and further from
/// the model's own values than the replay can resolve.
bool significant(const Fitted& f, const QuestionOptions& options);
/// The first of significant()'s conditions a fit fails, and for which of its effects.
struct Shortfall {
  enum class Kind { kNone, kFitFailed, kBelowSignificance, kTooSmall, kUnresolved };
  Kind kind = Kind::kNone;
  std::size_t effect = 0;
};
Shortfall shortfall(const Fitted& f, const QuestionOptions& options);
/// Indices of the singles fitted on every window (`full`; nullptr: all) whose fit succeeded with
/// a BIC below `below`, best (lowest BIC) first.
std::vector<std::size_t> singles_by_bic(const std::vector<Fitted>& singles,
                                        const std::vector<char>* full, double below);
/// The single effect to select: the best (by BIC) of those fitted on every window that is
/// significant and better than the nominal model (`nominal_bic`); none: nullptr.
const Fitted* choose_single(const std::vector<Fitted>& singles, const std::vector<char>& full,
                            double nominal_bic, const QuestionOptions& options);
/// The candidate to put a detected gap (the misfit test `gap`) down to (QuestionOptions::
/// min_z_attribute): the best (by BIC) of the singles fitted on every window and better than
/// the nominal model, when it is significant at min_z_attribute, large enough to matter,
/// resolved at that level and, for a gap of jumps, has fewer parameters than there are jumps;
/// none (nullptr) when the best one is not, whatever the others.
const Fitted* choose_attribution(const std::vector<Fitted>& singles, const std::vector<char>& full,
                                 double nominal_bic, const MisfitTest& gap,
                                 const QuestionOptions& options);
/// Whether the chosen effect leaves a pattern a second effect could take.
bool pattern_left(const std::vector<MisfitTest>& left, const QuestionOptions& options);
/// Whether a single candidate other than `chosen` is significant on its own: evidence of a
/// second effect even when the chosen one leaves no pattern the misfit tests see.
bool another_significant(const std::vector<Fitted>& singles, const Fitted* chosen,
                         const QuestionOptions& options);
/// The singles to try beside the chosen one, best first (by BIC against the nominal model on
/// the stretch each was fitted on).
std::vector<std::size_t> pair_order(const std::vector<Fitted>& singles);
/// The best significant pair better than `chosen` (nullptr: none).
const Fitted* choose_pair(const std::vector<Fitted>& pairs, const Fitted& chosen,
                          const QuestionOptions& options);

// --- Verdict (verdict.cpp) ---

/// The first misfit test (most significant first) that makes the residual unexplained.
const MisfitTest* counting_misfit(const std::vector<MisfitTest>& misfits,
                                  const QuestionOptions& options);

struct VerdictInputs {
  Question question = Question::kSensorToPose;
  const RobotModel* base = nullptr;
  const std::vector<Fitted>* singles = nullptr;
  const Fitted* chosen = nullptr;           ///< none: nothing selected
  const Fitted* final = nullptr;            ///< the selection refitted
  const std::vector<char>* full = nullptr;  ///< per single: fitted on every window (none: all)
  double nominal_bic = kInf;                ///< the nominal model's, every window
  /// The nominal model as the singles were scored against (nuisance fixed, every window) and
  /// the windows' start times: where an undecided candidate takes the gap. None: not said.
  const FitOutcome* nominal = nullptr;
  const std::vector<double>* window_start_s = nullptr;
};

/// Effect e of a fit, its parameters from `first` on (`s`: the fit's score), as reported.
FittedEffect fitted_effect(const Fitted& fit, const CandidateScore& s, std::size_t e,
                           std::size_t first);

/// Sets result.verdict and result.summary from result.misfits and the selection, and when
/// named, result.named and result.augmented; when nothing was selected, result.undecided.
void give_verdict(const VerdictInputs& in, const QuestionOptions& options, QuestionResult& result);

// --- Calibration (calibrate.cpp) ---

/// The single to calibrate with (QuestionOptions::calibrate): the best by BIC of the singles
/// fitted on every window whose effect has a parameter in the robot model, significant at
/// min_z_calibrate and resolved, and better than the nominal model; none: nullptr.
const Fitted* choose_calibration(const VerdictInputs& in, const QuestionOptions& options);
/// When the verdict is "no significant gap" and options.calibrate: result.calibrated,
/// result.augmented and a sentence in result.summary from choose_calibration().
void calibrate_own_parameters(const VerdictInputs& in, const QuestionOptions& options,
                              QuestionResult& result);

// --- The stages (question.cpp) ---

void measure_nominal(QuestionState& s, Question question);
void fit_nominal(QuestionState& s, const QuestionOptions& options);
void screen_singles(QuestionState& s, const std::vector<Candidate>& library,
                    const QuestionOptions& options);
void select_effects(QuestionState& s, const std::vector<Candidate>& library,
                    const QuestionOptions& options);
void refit_selection(QuestionState& s, const QuestionOptions& options);
void measure_misfit(const QuestionState& s, QuestionResult& result);
/// A jump left in a window where a selected effect changed the prediction by more than
/// 1 / kRemnantShare times what is left there is what that effect's approximate form leaves
/// of the change it brings (a lag fitted as first order where a servo has inertia), not
/// another effect.
inline constexpr double kRemnantShare = 0.5;
/// Marks the jumps tests (MisfitTest::remnant) every jump of which is such a remnant, from the
/// residual before (the nominal model's) and after (the selection's), channel-major.
void mark_remnant_jumps(const QuestionReplay& replay, const std::vector<double>& before,
                        const std::vector<double>& after, std::vector<MisfitTest>& misfits);
/// With nothing selected and a misfit test that counts: the candidate choose_attribution()
/// gives, refitted as the selection; kept (s.chosen set, result's misfit measures and
/// attributed_gap replaced) when no misfit test counts with it, else the state is restored.
void attribute_gap(QuestionState& s, const QuestionOptions& options, QuestionResult& result);

/// The channels whose fitted noise at rest (`noise`) is at least `min_ratio` times (in sigma)
/// the replay's stated variance, largest ratio first.
std::vector<NoiseFinding> stated_noise_findings(const QuestionReplay& replay,
                                                const NoiseModel& noise, double min_ratio);

}  // namespace swivel::model_gap::detail
