// SPDX-License-Identifier: Apache-2.0
#pragma once
// Scoring the model-gap workflow on runs whose truth is known: a result of analyse_gap is
// compared with what the generator hid. Shared by the benchmark (development runs from
// tests/independent_robot, validation runs from tests/second_robot) and the tests, so that all
// apply the same rules:
//   clean    both questions: no significant gap;
//   library  each question names exactly the hidden effects that belong to it (and sees no
//            gap when none does);
//   outside  no library effect is named by either question, except those the case allows
//            (a slippery floor may be named `slip`, the library's nearest law).

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "swivel/independent/battery.hpp"
#include "swivel/model_gap/workflow.hpp"

namespace swivel::model_gap::battery {

enum class RunKind { kClean, kLibrary, kOutside };

/// One hidden library effect with every parameter (the generators' key names; limits under
/// `accel_limit` / `steering_rate_limit`).
struct HiddenEffect {
  std::string effect;
  std::vector<std::pair<std::string, double>> params;
};

/// One hidden parameter against what the workflow fitted for it.
struct ParamCheck {
  std::string effect;
  std::string key;  ///< the workflow's key (limits: the model's `limits:` key)
  double truth = 0.0;
  double value = 0.0;
  double sigma = 0.0;  ///< infinite: not observable on its own
  [[nodiscard]] bool observable() const;
  [[nodiscard]] double deviation() const;  ///< |value - truth| / sigma
};

/// A single-effect candidate fitted on a run: its significance (a normal deviate under the
/// null), the effect and the run, so that a tail under the null can be traced to its fits.
struct SingleFit {
  double z = 0.0;
  std::string effect;
  std::string run;
};

struct CaseOutcome {
  std::string id;
  std::string robot;
  RunKind kind = RunKind::kClean;
  bool swpc = false;
  double row_rate_hz = 0.0;                        ///< from the run's median row interval
  std::vector<std::string> tags;                   ///< groups for breakdowns, e.g. "robot trike3"
  std::array<std::vector<std::string>, 2> hidden;  ///< per question (sensor, command)
  std::array<std::vector<std::string>, 2> named;   ///< per question: named effects
  std::array<Verdict, 2> verdict = {Verdict::kNoSignificantGap, Verdict::kNoSignificantGap};
  std::array<std::string, 2> summary;
  /// Per question: the candidate a verdict with nothing named leans towards (Undecided), or
  /// empty.
  std::array<std::string, 2> undecided;
  /// Sensor question: channels whose noise is larger than the model states (NoiseFinding).
  std::vector<std::string> noise_findings;
  /// Sensor question: the largest ratio over channels of the noise every window has to what
  /// the model's figures state (0 when none is stated).
  double max_noise_ratio = 0.0;
  /// Per question: each single-effect candidate's significance (z, a normal deviate under the
  /// null), for the calibration of clean runs.
  std::array<std::vector<SingleFit>, 2> single_fits;
  bool correct = false;  ///< the case's rule holds
  /// Every named hidden effect within 3 sigma of its truth, jointly over its parameters (on
  /// the combinations the run fixes; the rest the workflow leaves at the model's values).
  bool values_within_3_sigma = false;
  std::vector<double> effect_deviation_z;  ///< per named hidden effect: that joint distance
  /// Sensor question: what it calibrated (QuestionOptions::calibrate), and per calibrated
  /// effect the same joint distance from its truth (the hidden value, else the model's own).
  std::vector<std::string> calibrated;
  std::vector<double> calibration_deviation_z;
  std::string problem;                        ///< why not correct, for the report
  std::vector<ParamCheck> params;             ///< hidden parameters the workflow named
  std::array<double, 2> position_before_m{};  ///< final position error of each replay, before
  std::array<double, 2> position_after_m{};
  double wall_time_s = 0.0;
  double cpu_time_s = 0.0;  ///< CPU time of this thread's analysis
  std::string error;        ///< the workflow threw: its message (the case counts as wrong)
  /// Library runs of the second generator whose hidden effect is drivetrain geometry: whether
  /// the body's motion carries its size (swivel::second::GeometryFootprint); unset otherwise.
  std::optional<bool> size_in_motion;
  /// Caster runs of the second generator: the largest caster's median servo error while the
  /// robot drives (swivel::second::driving_servo_errors_rad()), and whether its servos fight
  /// their tyres (swivel::second::kFightingServoErrorRad); unset otherwise.
  std::optional<double> driving_servo_error_rad;
  std::optional<bool> servos_fighting;
  /// Caster runs whose command question was asked: the servos' yield it fitted
  /// (GapResult::steering_yield_rad); and, for the second generator's, the truth's
  /// (swivel::second::friction_limit_servo_errors_rad(), the median over its casters).
  std::optional<double> fitted_steering_yield_rad;
  std::optional<double> true_steering_yield_rad;
};

/// Scores `result` against what was hidden. `allowed_outside`: effects an outside case may
/// name without being wrong.
CaseOutcome score(const std::string& id, RunKind kind, const std::vector<HiddenEffect>& hidden,
                  const GapResult& result, const std::vector<std::string>& allowed_outside = {});

/// Reads the two files as a user would (the project's readers), analyses them and scores the
/// result; a workflow that throws gives an outcome with `error` set and `correct` false.
CaseOutcome analyse_and_score(const std::string& id, RunKind kind, const std::string& run_csv,
                              const std::string& model_yaml,
                              const std::vector<HiddenEffect>& hidden,
                              const std::vector<std::string>& allowed_outside = {},
                              const GapOptions& options = {});

/// Generates and analyses one case of the independent battery (the development runs).
CaseOutcome run_case(const independent::BatteryCase& c, const GapOptions& options = {});

}  // namespace swivel::model_gap::battery
