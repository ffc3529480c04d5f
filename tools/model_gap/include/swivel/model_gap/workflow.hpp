#pragma once
// The model-gap workflow of DESIGN.md: replay a run with the nominal model, locate the
// disagreement, fit named candidate effects (singly and in pairs), select by BIC and
// held-out validation, and replay again with the augmented model.

#include <string>
#include <vector>

#include "swivel/model_gap/channels.hpp"
#include "swivel/model_gap/fit.hpp"
#include "swivel/model_gap/locate.hpp"
#include "swivel/model_gap/run_data.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::model_gap {

/// When the evidence is strong enough to name an effect. Residuals are whitened by each
/// channel's noise level (estimated from the nominal residual's sample-to-sample scatter).
struct GapOptions {
  double holdout_fraction = 0.3;   ///< last part of the run, scored but not fitted
  double fit_rate_hz = 10.0;       ///< residual rows per second and channel
  /// Below this whitened RMS (on the held-out part, worst channel) the nominal model already
  /// agrees with the run to within its noise: nothing is named.
  double min_gap_whitened_rms = 6.0;
  /// Share of the held-out residual above the noise level (whitened sum of squares minus one
  /// per row) a selection must remove; the same share is required on the fitted part.
  double min_explained = 0.9;
  /// Each named effect's parameters must lie this many standard deviations (Mahalanobis,
  /// jointly over the effect's parameters) from their identity values.
  double min_significance = 4.0;
  /// A second effect must remove this share of what the best single effect leaves
  /// (held-out) and lower the BIC by min_delta_bic.
  double min_pair_gain = 0.5;
  double min_delta_bic = 10.0;
  /// Best singles combined into pairs (only when the best single leaves a significant gap).
  std::size_t pair_pool = 4;
  /// Runs whose training part is much longer than this are screened: every effect is fitted
  /// on the first screening_window_s, and the refit_count best are refitted on the whole
  /// training part (the others keep their screening values, scored on the whole run).
  double screening_window_s = 20.0;
  std::size_t refit_count = 2;
  FitOptions fit;
};

/// Parameters of one named effect as fitted.
struct FittedEffect {
  std::string name;
  EffectParams values;
  EffectParams sigmas;  ///< one standard deviation
};

/// One candidate (a single effect or a pair) after fitting.
struct CandidateScore {
  std::vector<std::string> effects;
  bool ok = false;
  std::vector<std::string> param_names;  ///< "effect.param"
  std::vector<double> values;
  std::vector<double> sigmas;
  double bic = 0.0;
  double delta_bic = 0.0;             ///< against the nominal model (negative is better)
  /// (rss_nominal - rss) / (rss_nominal - rows): share of the residual above noise removed.
  double explained_training = 0.0;
  double explained_validation = 0.0;
  int iterations = 0;
  [[nodiscard]] std::string label() const;
};

/// The gap of one channel before and after augmentation.
struct ChannelReport {
  ChannelInfo info;
  double noise_sigma = 0.0;     ///< whitening scale, channel units
  double rms_before = 0.0;
  double rms_after = 0.0;
  double final_before = 0.0;    ///< residual at the last sample where it exists
  double final_after = 0.0;
  double whitened_rms_validation_before = 0.0;
  double whitened_rms_validation_after = 0.0;
  Character character_before;
  Character character_after;
  std::vector<GrowthWindow> windows;  ///< where the nominal residual grows
  std::vector<PhaseStat> phases;      ///< nominal residual per phase
};

/// Pose error of one question (sensor-to-pose or command-to-pose) before and after.
struct PoseGap {
  Question question = Question::kSensorToPose;
  double rms_position_m_before = 0.0;
  double rms_position_m_after = 0.0;
  double final_position_m_before = 0.0;
  double final_position_m_after = 0.0;
  double rms_heading_rad_before = 0.0;
  double rms_heading_rad_after = 0.0;
  double final_heading_rad_before = 0.0;
  double final_heading_rad_after = 0.0;
};

enum class Verdict { kNoSignificantGap, kNamed, kUnexplained };

/// "no significant gap", "named", "unexplained residual".
const char* verdict_name(Verdict v);

struct GapResult {
  Verdict verdict = Verdict::kNoSignificantGap;
  std::string summary;                   ///< one readable sentence
  std::vector<FittedEffect> named;
  std::vector<CandidateScore> candidates;  ///< best BIC first
  std::vector<ChannelReport> channels;
  std::vector<PoseGap> pose_gaps;
  std::vector<PhaseSegment> segments;
  Character unexplained_character;       ///< of the worst channel, when unexplained
  std::string unexplained_channel;
  RobotModel nominal;
  RobotModel augmented;
  std::vector<double> t_s;
  ChannelSet measured;
  ChannelSet before;
  ChannelSet after;
  double holdout_start_s = 0.0;
  double worst_whitened_rms_before = 0.0;
  std::string worst_channel_before;
  GapOptions options;
  double wall_time_s = 0.0;
  std::string run_source;
};

/// Runs the workflow on a run with its nominal model.
/// @throws std::invalid_argument when the run does not fit the model (drivetrain, modules).
GapResult analyse_gap(const RobotModel& nominal, const RunData& run, const GapOptions& options = {});

/// Writes DIR/report.json, DIR/report.md, DIR/model_augmented.yaml and PNG plots (when
/// gnuplot is available; the report says so when it is not). Creates DIR.
/// @throws std::runtime_error when DIR or a file cannot be written.
void write_report(const GapResult& result, const std::string& dir);

}  // namespace swivel::model_gap
