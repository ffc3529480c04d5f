// SPDX-License-Identifier: Apache-2.0
#pragma once
// Scoring the model-gap workflow on the independent battery (tests/independent_robot): each
// case's run is generated, analysed as a user would (its run log and nominal model read
// back from text), and the verdicts compared with what the generator hid. Shared by the
// battery benchmark and the battery test so that both apply the same rules:
//   clean    both questions: no significant gap;
//   single,  each question names exactly the hidden effects that belong to it (and sees no
//   pair     gap when none does);
//   outside  nothing is named by either question.

#include <string>
#include <vector>

#include "swivel/independent/battery.hpp"
#include "swivel/model_gap/workflow.hpp"

namespace swivel::model_gap::battery {

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

struct CaseOutcome {
  std::string id;
  std::string robot;
  independent::CaseKind kind = independent::CaseKind::kClean;
  std::vector<std::string> hidden[2];  ///< per question (sensor, command): hidden effects
  std::vector<std::string> named[2];   ///< per question: named effects
  Verdict verdict[2] = {Verdict::kNoSignificantGap, Verdict::kNoSignificantGap};
  std::string summary[2];
  bool correct = false;  ///< the case's rule holds
  /// Every named hidden effect within 3 sigma of its truth, jointly over its parameters (on
  /// the combinations the run fixes; the rest the workflow leaves at the model's values).
  bool values_within_3_sigma = false;
  std::vector<double> effect_deviation_z;  ///< per named hidden effect: that joint distance
  std::string problem;                     ///< why not correct, for the report
  std::vector<ParamCheck> params;          ///< hidden parameters the workflow named
  double position_before_m[2] = {0, 0};    ///< final position error of each replay, before
  double position_after_m[2] = {0, 0};
  double wall_time_s = 0.0;
  /// CPU time of the analysis (the workflow runs on one thread): the figure to hold against
  /// the target when other work shares the machine.
  double cpu_time_s = 0.0;
};

/// Generates and analyses one case.
CaseOutcome run_case(const independent::BatteryCase& c, const GapOptions& options = {});

}  // namespace swivel::model_gap::battery
