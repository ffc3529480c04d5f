// SPDX-License-Identifier: Apache-2.0
#include "battery_scoring.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
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

// The generators name a limit's parameters after the effect; the workflow writes them to
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

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The rule of the case's kind, question by question.
bool judge(CaseOutcome& out, const std::vector<std::string>& allowed_outside) {
  std::ostringstream problem;
  bool correct = true;
  for (std::size_t i = 0; i < 2; ++i) {
    std::vector<std::string> hidden = out.hidden[i];
    std::vector<std::string> named = out.named[i];
    std::sort(hidden.begin(), hidden.end());
    std::sort(named.begin(), named.end());
    const char* question = i == 0 ? "sensor to pose" : "command to motion";
    if (out.kind == RunKind::kOutside) {
      std::vector<std::string> wrong;
      for (const auto& n : named) {
        if (std::find(allowed_outside.begin(), allowed_outside.end(), n) == allowed_outside.end()) {
          wrong.push_back(n);
        }
      }
      if (!wrong.empty()) {
        correct = false;
        problem << question << " named " << list(wrong) << " for an effect outside the library; ";
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
  out.problem = problem.str();
  return correct;
}

// What the sensor question calibrated, and how far from its truth (score()).
void score_calibration(const std::vector<HiddenEffect>& hidden, const QuestionResult& sensor,
                       CaseOutcome& out) {
  for (const FittedEffect& f : sensor.calibrated) {
    out.calibrated.push_back(f.name);
    std::vector<double> difference(f.fit_values.size(), 0.0);
    for (std::size_t i = 0; i < difference.size() && i < f.identity.size(); ++i)
      difference[i] = f.fit_values[i] - f.identity[i];
    for (const auto& e : hidden) {
      if (e.effect != f.name) continue;
      for (const auto& [generator_key, truth] : e.params) {
        const auto k =
            std::find(f.keys.begin(), f.keys.end(), workflow_key(e.effect, generator_key));
        if (k == f.keys.end()) continue;
        const auto at = static_cast<std::size_t>(k - f.keys.begin());
        if (at < difference.size() && at < f.inverse.size())
          difference[at] = f.fit_values[at] - (f.inverse[at] != 0 ? 1.0 / truth : truth);
      }
    }
    std::size_t rank = 0;
    double z = std::numeric_limits<double>::infinity();
    if (f.fit_covariance.size() == difference.size() * difference.size()) {
      const double chi2 = mahalanobis_squared(difference, f.fit_covariance, rank);
      z = rank > 0 ? chi_square_z(chi2, static_cast<double>(rank)) : 0.0;
    }
    out.calibration_deviation_z.push_back(z);
  }
}

}  // namespace

bool ParamCheck::observable() const { return std::isfinite(sigma) && sigma > 0.0; }

double ParamCheck::deviation() const {
  return observable() ? std::abs(value - truth) / sigma : std::numeric_limits<double>::infinity();
}

CaseOutcome score(const std::string& id, RunKind kind, const std::vector<HiddenEffect>& hidden,
                  const GapResult& r, const std::vector<std::string>& allowed_outside) {
  CaseOutcome out;
  out.id = id;
  out.kind = kind;
  out.robot = r.nominal.name;
  out.swpc = r.nominal.drivetrain == DrivetrainKind::kSwpc;
  if (out.swpc && r.command_assessed) out.fitted_steering_yield_rad = r.steering_yield_rad;
  for (const auto& e : hidden) out.hidden[index_of(question_of(e.effect))].push_back(e.effect);
  for (const QuestionResult* q : {&r.sensor, &r.command}) {
    const std::size_t i = index_of(q->question);
    out.verdict[i] = q->verdict;
    out.summary[i] = q->summary;
    if (q->undecided) out.undecided[i] = q->undecided->candidate.label();
    for (const FittedEffect& f : q->named) out.named[i].push_back(f.name);
    for (const CandidateScore& c : q->candidates) {
      if (c.effects.size() == 1 && c.ok && !c.z.empty())
        out.single_fits[i].push_back({c.z.front(), c.effects.front(), id});
    }
  }
  for (const NoiseFinding& f : r.sensor.noise_findings)
    out.noise_findings.push_back(f.channel.name);
  for (const ChannelGap& c : r.sensor.channels) {
    if (c.stated_sigma > 0.0)
      out.max_noise_ratio = std::max(out.max_noise_ratio, c.rest_sigma / c.stated_sigma);
  }
  for (const PoseGap& g : r.pose_gaps) {
    out.position_before_m[index_of(g.question)] = g.final_position_m_before;
    out.position_after_m[index_of(g.question)] = g.final_position_m_after;
  }
  out.correct = judge(out, allowed_outside);

  // Values of the hidden parameters that were named.
  out.values_within_3_sigma = out.correct;
  for (const auto& e : hidden) {
    const QuestionResult& q =
        question_of(e.effect) == Question::kSensorToPose ? r.sensor : r.command;
    const auto f = std::find_if(q.named.begin(), q.named.end(),
                                [&](const FittedEffect& x) { return x.name == e.effect; });
    if (f == q.named.end()) continue;
    std::vector<double> difference(f->keys.size(), 0.0);
    for (const auto& [generator_key, truth] : e.params) {
      const std::string key = workflow_key(e.effect, generator_key);
      const auto k = std::find(f->keys.begin(), f->keys.end(), key);
      if (k == f->keys.end()) continue;
      const auto at = static_cast<std::size_t>(k - f->keys.begin());
      out.params.push_back({e.effect, key, truth, f->values[at], f->sigmas[at]});
      if (at < f->fit_values.size() && at < f->inverse.size()) {
        const double truth_fit = f->inverse[at] != 0 ? 1.0 / truth : truth;
        difference[at] = f->fit_values[at] - truth_fit;
      }
    }
    // Jointly, over the combinations the run fixes.
    std::size_t rank = 0;
    double z = std::numeric_limits<double>::infinity();
    if (f->fit_covariance.size() == difference.size() * difference.size()) {
      const double chi2 = mahalanobis_squared(difference, f->fit_covariance, rank);
      z = rank > 0 ? chi_square_z(chi2, static_cast<double>(rank)) : 0.0;
    }
    out.effect_deviation_z.push_back(z);
    if (!(z <= 3.0)) out.values_within_3_sigma = false;
  }
  score_calibration(hidden, r.sensor, out);
  return out;
}

CaseOutcome analyse_and_score(const std::string& id, RunKind kind, const std::string& run_csv,
                              const std::string& model_yaml,
                              const std::vector<HiddenEffect>& hidden,
                              const std::vector<std::string>& allowed_outside,
                              const GapOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = thread_cpu_s();
  CaseOutcome out;
  double rate = 0.0;
  try {
    std::istringstream csv(run_csv);
    const RunLog log = parse_run_log(csv, id + ".csv");
    if (log.samples.size() > 1) {
      std::vector<double> dt;
      for (std::size_t i = 1; i < log.samples.size(); ++i) {
        dt.push_back(log.samples[i].t_s - log.samples[i - 1].t_s);
      }
      std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2),
                       dt.end());
      rate = 1.0 / dt[dt.size() / 2];
    }
    const RunData run = to_run_data(log);
    const RobotModel nominal = parse_robot_model(model_yaml, id + ".yaml");
    const GapResult r = analyse_gap(nominal, run, options);
    out = score(id, kind, hidden, r, allowed_outside);
  } catch (const std::exception& e) {
    out.id = id;
    out.kind = kind;
    out.error = e.what();
    out.problem = std::string("the workflow failed: ") + e.what();
    out.correct = false;
    for (const auto& h : hidden) out.hidden[index_of(question_of(h.effect))].push_back(h.effect);
  }
  out.row_rate_hz = rate;
  out.cpu_time_s = thread_cpu_s() - cpu_start;
  out.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

CaseOutcome run_case(const independent::BatteryCase& c, const GapOptions& options) {
  const independent::GeneratedRun files = independent::generate(c.spec);
  std::vector<HiddenEffect> hidden;
  for (const auto& e : c.expected) {
    HiddenEffect h{e.effect, {}};
    for (const auto& p : e.params) h.params.emplace_back(p.key, p.value);
    hidden.push_back(std::move(h));
  }
  const RunKind kind = c.kind == independent::CaseKind::kClean     ? RunKind::kClean
                       : c.kind == independent::CaseKind::kOutside ? RunKind::kOutside
                                                                   : RunKind::kLibrary;
  CaseOutcome out =
      analyse_and_score(c.id, kind, files.run_csv, files.nominal_model_yaml, hidden, {}, options);
  out.robot = c.robot;
  out.tags = {"robot " + c.robot};
  return out;
}

}  // namespace swivel::model_gap::battery
