// SPDX-License-Identifier: Apache-2.0
#include "validation_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace swivel::model_gap::validation {
namespace {

std::string percent(const Proportion& p) {
  char buf[96];
  if (p.n == 0) return "no runs";
  const Interval ci = p.interval();
  std::snprintf(buf, sizeof buf, "%zu/%zu = %.1f %% [%.1f, %.1f]", p.hits, p.n, 100.0 * p.value(),
                100.0 * ci.low, 100.0 * ci.high);
  return buf;
}

TargetResult proportion_target(const std::string& name, const Proportion& p, double low,
                               double high) {
  TargetResult t;
  t.name = name;
  char buf[64];
  if (low <= 0.0) {
    std::snprintf(buf, sizeof buf, "<= %.0f %%", 100.0 * high);
  } else if (high >= 1.0) {
    std::snprintf(buf, sizeof buf, ">= %.0f %%", 100.0 * low);
  } else {
    std::snprintf(buf, sizeof buf, "%.0f-%.0f %%", 100.0 * low, 100.0 * high);
  }
  t.target = buf;
  t.measured = percent(p);
  const double v = p.value();
  t.met = p.n > 0 && v >= low && v <= high;
  const Interval ci = p.interval();
  t.met_by_whole_interval = p.n > 0 && ci.low >= low && ci.high <= high;
  return t;
}

}  // namespace

Interval wilson_interval(std::size_t hits, std::size_t n, double z) {
  if (n == 0) return {0.0, 1.0};
  const auto nn = static_cast<double>(n);
  const double p = static_cast<double>(hits) / nn;
  const double z2 = z * z;
  const double centre = (p + z2 / (2 * nn)) / (1 + z2 / nn);
  const double half = z * std::sqrt(p * (1 - p) / nn + z2 / (4 * nn * nn)) / (1 + z2 / nn);
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

double Proportion::value() const {
  return n > 0 ? static_cast<double>(hits) / static_cast<double>(n)
               : std::numeric_limits<double>::quiet_NaN();
}

namespace {

// Nothing named by either question that the run does not hide.
bool names_only_hidden(const battery::CaseOutcome& o) {
  if (!o.error.empty()) return false;
  for (const auto& named : o.named) {
    for (const std::string& n : named) {
      if (std::ranges::none_of(o.hidden, [&n](const std::vector<std::string>& h) {
            return std::ranges::find(h, n) != h.end();
          })) {
        return false;
      }
    }
  }
  return true;
}

// The undecided verdicts of a library or outside run (question.hpp, Undecided).
void add_undecided(const battery::CaseOutcome& o, SetFigures& f) {
  for (std::size_t q = 0; q < 2; ++q) {
    const std::vector<std::string>& hidden = o.hidden[q];
    const bool leans_hidden = std::ranges::find(hidden, o.undecided[q]) != hidden.end();
    if (o.kind == battery::RunKind::kLibrary && !hidden.empty() && o.named[q].empty())
      f.missed_undecided_hidden.add(leans_hidden);
    if (!o.undecided[q].empty()) f.undecided_not_hidden.add(!leans_hidden);
  }
}

}  // namespace

SetFigures figures(const std::vector<battery::CaseOutcome>& outcomes) {
  SetFigures f;
  double total_cpu = 0.0;
  f.slowest_clean_rate_hz = std::numeric_limits<double>::infinity();
  for (const auto& o : outcomes) {
    total_cpu += o.cpu_time_s;
    for (double z : o.calibration_deviation_z) f.calibrated_within_3_sigma.add(z <= 3.0);
    f.worst_cpu_s = std::max(f.worst_cpu_s, o.cpu_time_s);
    f.errors += o.error.empty() ? 0 : 1;
    switch (o.kind) {
      case battery::RunKind::kClean: {
        const bool sensor = !o.error.empty() || o.verdict[0] != Verdict::kNoSignificantGap;
        const bool command = !o.error.empty() || o.verdict[1] != Verdict::kNoSignificantGap;
        f.false_alarm.add(sensor || command);
        f.sensor_false_alarm.add(sensor);
        f.command_false_alarm.add(command);
        f.clean_noise_finding.add(!o.noise_findings.empty());
        f.clean_calibrated.add(!o.calibrated.empty());
        f.clean_undecided.add(!o.undecided[0].empty() || !o.undecided[1].empty());
        if (o.error.empty()) f.clean_noise_ratios.push_back(o.max_noise_ratio);
        for (std::size_t q = 0; q < 2; ++q) {
          f.clean_single_fits[q].insert(f.clean_single_fits[q].end(), o.single_fits[q].begin(),
                                        o.single_fits[q].end());
        }
        f.clean_robots.insert(o.robot);
        (o.swpc ? f.clean_swpc : f.clean_differential) = true;
        f.slowest_clean_rate_hz = std::min(f.slowest_clean_rate_hz, o.row_rate_hz);
        f.fastest_clean_rate_hz = std::max(f.fastest_clean_rate_hz, o.row_rate_hz);
        break;
      }
      case battery::RunKind::kLibrary:
        f.effect_noise_finding.add(!o.noise_findings.empty());
        f.named_right.add(o.correct && o.values_within_3_sigma);
        add_undecided(o, f);
        if (o.size_in_motion.value_or(true)) {
          f.named_right_size_in_motion.add(o.correct && o.values_within_3_sigma);
        } else {
          f.friction_limited_no_wrong_name.add(names_only_hidden(o));
        }
        if (o.servos_fighting.has_value()) {
          (*o.servos_fighting ? f.named_right_servos_fighting : f.named_right_servos_not_fighting)
              .add(o.correct && o.values_within_3_sigma);
        }
        for (const auto& p : o.params) {
          if (!p.observable()) continue;
          f.within_1_sigma.add(p.deviation() <= 1.0);
          f.within_3_sigma.add(p.deviation() <= 3.0);
        }
        break;
      case battery::RunKind::kOutside:
        f.effect_noise_finding.add(!o.noise_findings.empty());
        f.outside_right.add(o.correct);
        add_undecided(o, f);
        break;
    }
  }
  if (f.false_alarm.n == 0) f.slowest_clean_rate_hz = 0.0;
  f.mean_cpu_s = outcomes.empty() ? 0.0 : total_cpu / static_cast<double>(outcomes.size());
  return f;
}

std::vector<TargetResult> judge_targets(const SetFigures& f) {
  std::vector<TargetResult> out;
  out.push_back(proportion_target("false alarms, either question (clean runs)", f.false_alarm, 0.0,
                                  kMaxFalseAlarmRate));
  {
    TargetResult t;
    t.name = "clean runs span the targets' conditions";
    char buf[160];
    std::snprintf(
        buf, sizeof buf, ">= %zu runs, both drivetrains, >= %zu robots, rows <= %.0f to >= %.0f Hz",
        kMinCleanRuns, kMinCleanRobots, kSlowestRowRateAtMostHz, kFastestRowRateAtLeastHz);
    t.target = buf;
    std::snprintf(buf, sizeof buf, "%zu runs, %s%s, %zu robots, rows %.1f to %.1f Hz",
                  f.false_alarm.n, f.clean_differential ? "differential" : "",
                  f.clean_swpc ? (f.clean_differential ? " and swpc" : "swpc") : "",
                  f.clean_robots.size(), f.slowest_clean_rate_hz, f.fastest_clean_rate_hz);
    t.measured = buf;
    t.met = f.false_alarm.n >= kMinCleanRuns && f.clean_differential && f.clean_swpc &&
            f.clean_robots.size() >= kMinCleanRobots &&
            f.slowest_clean_rate_hz <= kSlowestRowRateAtMostHz &&
            f.fastest_clean_rate_hz >= kFastestRowRateAtLeastHz;
    t.met_by_whole_interval = t.met;
    out.push_back(t);
  }
  out.push_back(proportion_target("in-library effects named right, values within 3 sigma",
                                  f.named_right, kMinNamedRight, 1.0));
  out.push_back(proportion_target("coverage of the 1 sigma intervals", f.within_1_sigma,
                                  kMinCoverage1Sigma, kMaxCoverage1Sigma));
  out.push_back(proportion_target("coverage of the 3 sigma intervals", f.within_3_sigma,
                                  kMinCoverage3Sigma, 1.0));
  return out;
}

bool all_met(const std::vector<TargetResult>& results) {
  return std::all_of(results.begin(), results.end(), [](const TargetResult& t) { return t.met; });
}

double RepeatSpread::scatter_over_sigma() const {
  return mean_sigma > 0.0 ? scatter / mean_sigma : std::numeric_limits<double>::quiet_NaN();
}

std::vector<RepeatSpread> repeat_spread(const std::vector<battery::CaseOutcome>& repeats) {
  std::vector<std::vector<battery::ParamCheck>> groups;
  for (const battery::CaseOutcome& o : repeats) {
    for (const battery::ParamCheck& p : o.params) {
      if (!p.observable()) continue;
      auto g = std::find_if(groups.begin(), groups.end(), [&p](const auto& x) {
        return x.front().effect == p.effect && x.front().key == p.key;
      });
      if (g == groups.end()) {
        groups.push_back({p});
      } else {
        g->push_back(p);
      }
    }
  }
  std::vector<RepeatSpread> out;
  for (const auto& g : groups) {
    RepeatSpread s;
    s.effect = g.front().effect;
    s.key = g.front().key;
    s.truth = g.front().truth;
    s.n = g.size();
    const auto n = static_cast<double>(g.size());
    double sigma2 = 0.0;
    double z2 = 0.0;
    for (const battery::ParamCheck& p : g) {
      s.mean_value += p.value / n;
      sigma2 += p.sigma * p.sigma / n;
      z2 += p.deviation() * p.deviation() / n;
      s.within_1_sigma.add(p.deviation() <= 1.0);
    }
    double scatter2 = 0.0;
    for (const battery::ParamCheck& p : g) scatter2 += std::pow(p.value - s.mean_value, 2);
    s.scatter = g.size() > 1 ? std::sqrt(scatter2 / (n - 1.0)) : 0.0;
    s.mean_sigma = std::sqrt(sigma2);
    s.rms_deviation = std::sqrt(z2);
    out.push_back(std::move(s));
  }
  return out;
}

double normal_quantile(double p) {
  double lo = -40.0;
  double hi = 40.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace swivel::model_gap::validation
