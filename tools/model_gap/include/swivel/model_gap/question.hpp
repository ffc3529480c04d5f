// SPDX-License-Identifier: Apache-2.0
#pragma once
// One question of the workflow, decided on its own: fit the question's candidates to its
// window residuals, select effects by forward steps (the best single effect, then a second
// one only if it is significant in the pair), and give a verdict:
//   no significant gap    no candidate is significant and no misfit test fires;
//   named                 the selected effects are significant and large enough to matter
//                         (they move some channel by half its noise, RMS) and, with them
//                         added, every misfit test stays quiet;
//   unexplained residual  a misfit test fires: something the library does not hold
//                         remains, and nothing is named (a library effect that fits part
//                         of it would be a wrong name).
// A gap the misfit tests detect with no candidate significant enough to name unasked is put
// down to the best candidate when that takes the whole gap away (QuestionOptions::
// min_z_attribute): the detection is the misfit test's, the candidate only says which.
// Significance is a likelihood-ratio test of each effect against the fit without it,
// widened by how much the residuals' autocorrelation widens its parameters (the sandwich
// covariance of fit.hpp), expressed as a normal deviate.
// A verdict with nothing named says when the run leans towards one candidate all the same
// (Undecided): most of the gap, on too few windows to name it.

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "swivel/model_gap/channels.hpp"
#include "swivel/model_gap/fit.hpp"
#include "swivel/model_gap/library.hpp"
#include "swivel/model_gap/misfit.hpp"
#include "swivel/model_gap/noise_model.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::model_gap {

enum class Verdict { kNoSignificantGap, kNamed, kUnexplained };

/// "no significant gap", "named", "unexplained residual".
const char* verdict_name(Verdict v);

struct QuestionOptions {
  double min_z_name = 5.0;  ///< significance an effect needs to be named
  double min_z_misfit =
      5.0;  ///< significance at which a misfit test calls the residual unexplained
  /// Significance at which the best candidate (by BIC) names a gap a misfit test detected on
  /// the nominal residual, when nothing reached min_z_name and, with it, no misfit test counts.
  /// An effect that acts at a handful of steps (a steering lag while casters swing) rests on
  /// those few windows, and its F test with their few degrees of freedom stays below
  /// min_z_name however large the change it explains; the gap it takes away is already
  /// significant at min_z_misfit.
  double min_z_attribute = 3.0;
  /// Noise at rest this many times (in sigma) what the model's sensor figures give, or more, is
  /// reported as a NoiseFinding.
  double min_noise_ratio = 2.0;
  /// Size (noise sigmas, the largest over channels of the RMS change) below which a
  /// significant effect or misfit is still too small to matter.
  double min_effect_size = 0.5;
  /// Size a significant misfit must reach to make the residual unexplained (MisfitTest::size:
  /// the pattern at least as large as the noise around it): a replay is an approximation,
  /// and what it misses by a fraction of the noise is not a missing effect.
  double min_misfit_size = 1.0;
  /// Calibrate when nothing is named: the best candidate that is a parameter of the robot's
  /// own model (fold_effects.hpp) and significant at min_z_calibrate, whatever its change per
  /// window (a track width 1 % off changes each window by a fraction of the noise, and the
  /// whole run's path by centimetres). A better value of a parameter the model has, not a
  /// missing effect: reported apart from `named`, folded into the augmented model.
  bool calibrate = false;
  double min_z_calibrate = 3.0;
  std::size_t max_effects = 2;
  std::size_t pair_pool = 3;  ///< best single candidates tried as the second effect
  /// Screening of long runs: every candidate is first fitted on the first screen_fraction of
  /// the windows (at least screen_min_windows), and the refit_count best again on all.
  double screen_fraction = 0.35;
  std::size_t screen_min_windows = 40;
  std::size_t refit_count = 2;
  FitOptions fit;
};

/// How a question's channels are predicted: the replay behind it.
struct QuestionReplay {
  std::vector<ChannelInfo> channels;
  std::size_t windows = 0;
  /// Residuals (channel-major, channel units) of `model` with nuisance values `nuisance`,
  /// for the first `window_limit` windows (the rest NaN).
  std::function<bool(const RobotModel& model, std::span<const double> nuisance,
                     std::vector<double>& out, std::size_t window_limit)>
      residuals;
  /// Fitted with every candidate and never named (e.g. the commands' timing).
  std::vector<ParamSpec> nuisance;
  /// Fit the nuisance on the nominal model before the noise is measured, and measure the
  /// noise (and the "before" residual) with it: for nuisances that are not small against the
  /// noise (a motion-capture body's offset), which would otherwise inflate it.
  bool fit_nuisance_before_noise = false;
  /// Refit the nuisance beside every candidate (else it stays where the nominal model put it
  /// until the selection is refitted): for nuisances that trade against effects (a tracked
  /// body's offset against a wrong geometry), cheap to refit.
  bool refit_nuisance_with_candidates = false;
  std::vector<double> own_change;            ///< channel-major, for the misfit tests
  std::vector<std::vector<double>> noise_x;  ///< [channel][window], NoiseModel's x
  std::vector<double> noise_floor;           ///< per channel, variance
  /// Per channel, the variance per window the model's own sensor figures account for (motion
  /// capture at the window's ends, gyro noise, encoder quantization); empty: not stated. The
  /// fitted noise beyond it is reported (NoiseFinding), never silently taken as noise.
  std::vector<double> stated_variance;
  /// Per channel, which of the model's figures the stated variance comes from, for the report.
  std::vector<std::string> stated_source;
  /// Channel-major variance the replay itself adds in each window for a model and nuisance
  /// values (unset: none), e.g. from not knowing when in its row a step of the commands came.
  /// Measured first on the base model, then again on the selection.
  std::function<std::vector<double>(const RobotModel& model, std::span<const double> nuisance)>
      known_variance_of;
  std::vector<double> known_variance;  ///< the current one (set by analyse_question)
  std::vector<double> accel;           ///< per window
  std::vector<double> start_yaw_rad;   ///< per window
  std::vector<std::vector<double>> wheel_sin_change;
  std::vector<std::vector<double>> wheel_cos_change;
  std::vector<std::vector<double>> slowest_roll_offsets;  ///< MisfitInputs's
  std::vector<double> window_start_s;  ///< per window: its first row's time (for the report)
};

/// Parameters of one named effect as fitted, in the model's units.
struct FittedEffect {
  std::string name;
  bool limits = false;  ///< written to the model's `limits:` (else to `effects:`)
  std::vector<std::string> keys;
  std::vector<double> values;
  std::vector<double> sigmas;  ///< one standard deviation (infinite: not observable alone)
  /// One standard deviation of what the run fixes of each parameter (its part in the
  /// observable combinations); equals sigmas where a parameter is observable alone.
  std::vector<double> partial_sigmas;
  std::size_t observable_combinations = 0;  ///< of keys.size(); the rest left at the model's values
  double z = 0.0;                           ///< significance against the nominal model's values
  // In fit units (limits as 1 / limit), for checks against a known truth.
  std::vector<double> fit_values;
  std::vector<double> fit_covariance;  ///< row-major, resolution included, observable subspace
  std::vector<char> inverse;           ///< per key: fitted as 1 / value
  std::vector<double> identity;        ///< per key, fit units: the nominal model's own value
};

/// One candidate (a single effect or a pair) after fitting.
struct CandidateScore {
  std::vector<std::string> effects;
  bool ok = false;
  std::vector<std::string> param_names;  ///< "effect.key"
  std::vector<double> values;            ///< model units
  std::vector<double> sigmas;
  std::vector<double> z;     ///< per effect: significance
  std::vector<double> size;  ///< per effect: RMS change it brings, noise sigmas
  double bic = 0.0;
  double delta_bic = 0.0;  ///< against the nominal model (negative is better)
  double explained = 0.0;  ///< share of the nominal whitened sum of squares removed
  int iterations = 0;
  std::string label_note;  ///< e.g. how far it was fitted
  [[nodiscard]] std::string label() const;
};

/// A channel whose noise at rest (the fitted variance every window has, NoiseModel::a) is
/// larger than the model's sensor figures account for: the sensors are noisier than the model
/// says, or something the library does not hold varies from window to window. Either way the
/// fit took it as noise, and effects smaller than it stay hidden.
struct NoiseFinding {
  ChannelInfo channel;
  double measured_sigma = 0.0;  ///< sqrt(a), channel units per window
  double stated_sigma = 0.0;    ///< what the model's figures give
  double ratio = 0.0;           ///< measured / stated
  std::string source;           ///< the figures, e.g. "motion_capture.yaw_noise_rad 0.001"
};

/// The gap of one channel before and after.
struct ChannelGap {
  ChannelInfo info;
  double noise_sigma = 0.0;  ///< median over windows, channel units
  double rest_sigma = 0.0;   ///< what every window has (sqrt of NoiseModel::a)
  double stated_sigma = std::numeric_limits<double>::quiet_NaN();  ///< the model's figures' part
  double rms_before = 0.0;  ///< window residuals, channel units
  double rms_after = 0.0;
  double whitened_rms_before = 0.0;
  double whitened_rms_after = 0.0;
};

/// Nothing named, yet one single candidate (the best by BIC) takes more than kUndecidedShare
/// of what the nominal model leaves, and would pass as significant were its evidence spread
/// over many windows; it rests on a few (a handful of command steps or turns' starts), and
/// against so few it stays below the bar. Not a finding: the run leans towards it, and one
/// with more of the motion it acts in would decide.
struct Undecided {
  CandidateScore candidate;
  double windows = 0.0;   ///< the windows its significance rests on
  double widening = 1.0;  ///< how much the residuals' correlation widened its variance
  double z_many = 0.0;    ///< its statistic against the normal, as on many windows
  /// Where it takes the gap: the start times of the (at most kUndecidedWhere) windows whose
  /// whitened sum of squares it lowers most, earliest first, and their share of all it lowers.
  std::vector<double> where_s{};
  double where_share = 0.0;
};

/// How many windows an undecided verdict points at.
inline constexpr std::size_t kUndecidedWhere = 3;

/// Share of the nominal model's whitened sum of squares above which a candidate that is not
/// named is reported as undecided. On clean runs the best candidate takes a few per cent at
/// most (7.4 % on the 240 of the fifth validation set), on a slippery floor up to 27 %.
inline constexpr double kUndecidedShare = 0.5;

struct QuestionResult {
  Question question = Question::kSensorToPose;
  Verdict verdict = Verdict::kNoSignificantGap;
  std::string summary;
  std::vector<FittedEffect> named;
  /// Calibrated (QuestionOptions::calibrate): set only when nothing was named or unexplained.
  std::vector<FittedEffect> calibrated;
  std::vector<CandidateScore> candidates;  ///< best BIC first
  std::vector<MisfitTest> misfits;         ///< on the residual that remains, most significant first
  std::vector<ChannelGap> channels;
  std::vector<NoiseFinding> noise_findings;  ///< largest ratio first
  std::vector<double> nuisance;              ///< fitted nuisance values (with the selection)
  std::vector<double> nuisance_sigmas;       ///< their 1-sigma (infinite: not fixed by the run)
  std::vector<double> residuals_before;      ///< channel-major, channel units
  std::vector<double> residuals_after;
  RobotModel augmented;  ///< base plus the named (or calibrated) effects
  /// Named by attribution (QuestionOptions::min_z_attribute): the misfit test that detected
  /// the gap on the nominal residual, which the named effects take away. Empty otherwise.
  std::vector<MisfitTest> attributed_gap;
  /// Named, one effect: other single candidates significant on their own whose BIC is within
  /// kRivalBic of the named one's, best first. The run barely tells them apart (on circles
  /// alone a caster's steering offset turns the body as a wheel-radius change does).
  std::vector<CandidateScore> rivals;
  /// Nothing selected (no significant gap, or unexplained): the candidate the run leans
  /// towards, if any (give_verdict()).
  std::optional<Undecided> undecided;
  double wall_time_s = 0.0;
};

/// BIC apart below which a significant rival is reported beside a named effect: under 6 the
/// evidence for the named one over it is less than strong (posterior odds below 20 : 1).
inline constexpr double kRivalBic = 6.0;

/// Decides one question on `base` (the model the question starts from).
QuestionResult analyse_question(Question question, const RobotModel& base,
                                const QuestionReplay& replay, const std::vector<Candidate>& library,
                                const QuestionOptions& options);

}  // namespace swivel::model_gap
