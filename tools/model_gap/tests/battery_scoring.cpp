// SPDX-License-Identifier: Apache-2.0
#include "battery_scoring.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <sstream>

#include "swivel/independent/generator.hpp"
#include "swivel/model_gap/fit.hpp"
#include "swivel/model_gap/library.hpp"
#include "swivel/model_gap/run_log_adapter.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_log.hpp"

namespace swivel::model_gap::battery {
namespace {

std::size_t index_of(Question q) { return q == Question::kSensorToPose ? 0 : 1; }

// The generator names a limit's parameters after the effect; the workflow writes them to
// the model's `limits:` section under its keys.
std::string workflow_key(const std::string& effect, const std::string& key) {
  if (effect == "accel_limit" && key == "linear_mps2") return "linear_acceleration_mps2";
  if (effect == "accel_limit" && key == "angular_radps2") return "angular_acceleration_radps2";
  if (effect == "steering_rate_limit" && key == "radps") return "steering_rate_radps";
  return key;
}

std::string list(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& e : v) s += (s.empty() ? "" : "+") + e;
  return s.empty() ? "nothing" : s;
}

}  // namespace

bool ParamCheck::observable() const { return std::isfinite(sigma) && sigma > 0.0; }

double ParamCheck::deviation() const {
  return observable() ? std::abs(value - truth) / sigma : std::numeric_limits<double>::infinity();
}

CaseOutcome run_case(const independent::BatteryCase& c, const GapOptions& options) {
  CaseOutcome out;
  out.id = c.id;
  out.robot = c.robot;
  out.kind = c.kind;
  const independent::GeneratedRun files = independent::generate(c.spec);
  std::istringstream csv(files.run_csv);
  const RunData run = to_run_data(parse_run_log(csv, c.id + ".csv"));
  const RobotModel nominal = parse_robot_model(files.nominal_model_yaml, c.id + ".yaml");

  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();
  const GapResult r = analyse_gap(nominal, run, options);
  out.cpu_time_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  out.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  for (const auto& e : c.expected) out.hidden[index_of(question_of(e.effect))].push_back(e.effect);
  for (const QuestionResult* q : {&r.sensor, &r.command}) {
    const std::size_t i = index_of(q->question);
    out.verdict[i] = q->verdict;
    out.summary[i] = q->summary;
    for (const FittedEffect& f : q->named) out.named[i].push_back(f.name);
  }
  for (const PoseGap& g : r.pose_gaps) {
    out.position_before_m[index_of(g.question)] = g.final_position_m_before;
    out.position_after_m[index_of(g.question)] = g.final_position_m_after;
  }

  // The rule of the case's kind, question by question.
  std::ostringstream problem;
  bool correct = true;
  for (std::size_t i = 0; i < 2; ++i) {
    std::vector<std::string> hidden = out.hidden[i];
    std::vector<std::string> named = out.named[i];
    std::sort(hidden.begin(), hidden.end());
    std::sort(named.begin(), named.end());
    const char* question = i == 0 ? "sensor to pose" : "command to motion";
    if (c.kind == independent::CaseKind::kOutside) {
      if (!named.empty()) {
        correct = false;
        problem << question << " named " << list(named) << " for an effect outside the library; ";
      }
    } else if (hidden.empty()) {
      if (out.verdict[i] != Verdict::kNoSignificantGap) {
        correct = false;
        problem << question << ": " << verdict_name(out.verdict[i]) << " (" << list(named)
                << ") where nothing is hidden; ";
      }
    } else if (out.verdict[i] != Verdict::kNamed || named != hidden) {
      correct = false;
      problem << question << ": " << verdict_name(out.verdict[i]) << " " << list(named)
              << ", hidden " << list(hidden) << "; ";
    }
  }
  out.correct = correct;
  out.problem = problem.str();

  // Values of the hidden parameters that were named.
  out.values_within_3_sigma = correct;
  for (const auto& e : c.expected) {
    const QuestionResult& q =
        question_of(e.effect) == Question::kSensorToPose ? r.sensor : r.command;
    const auto f = std::find_if(q.named.begin(), q.named.end(),
                                [&](const FittedEffect& x) { return x.name == e.effect; });
    if (f == q.named.end()) continue;
    std::vector<double> difference(f->keys.size(), 0.0);
    for (const auto& p : e.params) {
      const std::string key = workflow_key(e.effect, p.key);
      const auto k = std::find(f->keys.begin(), f->keys.end(), key);
      if (k == f->keys.end()) continue;
      const auto at = static_cast<std::size_t>(k - f->keys.begin());
      out.params.push_back({e.effect, key, p.value, f->values[at], f->sigmas[at]});
      const double truth_fit = f->inverse[at] ? 1.0 / p.value : p.value;
      difference[at] = f->fit_values[at] - truth_fit;
    }
    // Jointly, over the combinations the run fixes.
    std::size_t rank = 0;
    const double chi2 = mahalanobis_squared(difference, f->fit_covariance, rank);
    const double z = rank > 0 ? chi_square_z(chi2, static_cast<double>(rank)) : 0.0;
    out.effect_deviation_z.push_back(z);
    if (!(z <= 3.0)) out.values_within_3_sigma = false;
  }
  return out;
}

}  // namespace swivel::model_gap::battery
