// SPDX-License-Identifier: Apache-2.0
// The model-gap workflow on data it did not make: runs of the independent generator
// (tests/independent_robot), analysed as a user would.
//   swivel-bench-model-gap                  wall time on a 120 s run of each robot
//   swivel-bench-model-gap --battery        the whole battery: confusion table, false
//                                           alarms, named right, coverage, gap shrink, time
//   swivel-bench-model-gap --battery --subset | --case ID [--case ID ...]
// Targets: clean runs no significant gap 100 %; in-library effects named right (value within
// 3 sigma) 90 %; outside effects never named; 1-sigma coverage 60-75 %; under 10 s a run.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <map>
#include <string>
#include <vector>

#include "battery_scoring.hpp"
#include "swivel/cli/command_line.hpp"

namespace {

using swivel::independent::BatteryCase;
using swivel::independent::CaseKind;
using namespace swivel::model_gap;

std::string outcome_label(const battery::CaseOutcome& o, std::size_t q) {
  if (o.verdict[q] == Verdict::kNamed) {
    std::vector<std::string> named = o.named[q];
    std::sort(named.begin(), named.end());
    std::string s;
    for (const auto& n : named) s += (s.empty() ? "" : "+") + n;
    return s;
  }
  return verdict_name(o.verdict[q]);
}

std::string hidden_label(const battery::CaseOutcome& o, std::size_t q) {
  if (o.kind == CaseKind::kOutside) return "outside: " + o.id.substr(o.id.rfind('/') + 1);
  std::vector<std::string> hidden = o.hidden[q];
  if (hidden.empty()) return "nothing";
  std::sort(hidden.begin(), hidden.end());
  std::string s;
  for (const auto& h : hidden) s += (s.empty() ? "" : "+") + h;
  return s;
}

const char* yes(bool b) { return b ? "yes" : "NO"; }

int run_battery(const std::vector<BatteryCase>& cases) {
  std::vector<battery::CaseOutcome> outcomes;
  std::printf("%-44s %-34s %-34s %-4s %-5s %6s\n", "case", "sensor to pose", "command to motion",
              "ok", "3sig", "cpu");
  for (const BatteryCase& c : cases) {
    battery::CaseOutcome o = battery::run_case(c);
    std::printf("%-44s %-34s %-34s %-4s %-5s %5.1fs\n", o.id.c_str(), outcome_label(o, 0).c_str(),
                outcome_label(o, 1).c_str(), yes(o.correct),
                o.kind == CaseKind::kSingle || o.kind == CaseKind::kPair
                    ? yes(o.values_within_3_sigma)
                    : "-",
                o.cpu_time_s);
    if (!o.correct) std::printf("    %s\n", o.problem.c_str());
    for (const auto& p : o.params) {
      std::printf("    %s.%s: truth %.6g, fitted %.6g +- %.2g (%.1f sigma)\n", p.effect.c_str(),
                  p.key.c_str(), p.truth, p.value, p.sigma, p.deviation());
    }
    for (double z : o.effect_deviation_z) std::printf("    jointly %.1f sigma from the truth\n", z);
    std::fflush(stdout);
    outcomes.push_back(std::move(o));
  }

  std::printf("\nConfusion, per question (hidden -> what the question said; count):\n");
  for (std::size_t q = 0; q < 2; ++q) {
    std::printf("  %s\n", q == 0 ? "sensor to pose" : "command to motion");
    std::map<std::string, std::map<std::string, int>> table;
    for (const auto& o : outcomes) ++table[hidden_label(o, q)][outcome_label(o, q)];
    for (const auto& [hidden, said] : table) {
      std::printf("    %-36s ->", hidden.c_str());
      for (const auto& [label, count] : said) std::printf("  %s: %d", label.c_str(), count);
      std::printf("\n");
    }
  }

  int clean = 0, clean_ok = 0, library = 0, library_ok = 0, outside = 0, outside_ok = 0;
  int params = 0, within1 = 0, within3 = 0;
  double worst_time = 0.0, total_time = 0.0, worst_wall = 0.0;
  for (const auto& o : outcomes) {
    worst_time = std::max(worst_time, o.cpu_time_s);
    worst_wall = std::max(worst_wall, o.wall_time_s);
    total_time += o.cpu_time_s;
    if (o.kind == CaseKind::kClean) {
      ++clean;
      clean_ok += o.correct ? 1 : 0;
    } else if (o.kind == CaseKind::kOutside) {
      ++outside;
      outside_ok += o.correct ? 1 : 0;
    } else {
      ++library;
      library_ok += o.correct && o.values_within_3_sigma ? 1 : 0;
      for (const auto& p : o.params) {
        if (!p.observable()) continue;
        ++params;
        within1 += p.deviation() <= 1.0 ? 1 : 0;
        within3 += p.deviation() <= 3.0 ? 1 : 0;
      }
    }
  }
  const auto pct = [](int a, int b) { return b > 0 ? 100.0 * a / b : 0.0; };
  std::printf("\n%zu runs\n", outcomes.size());
  std::printf(
      "  clean runs with no significant gap (both questions): %d/%d = %.0f %%  (target 100 %%; "
      "false-alarm rate %.0f %%)\n",
      clean_ok, clean, pct(clean_ok, clean), 100.0 - pct(clean_ok, clean));
  std::printf(
      "  in-library effects named right, values within 3 sigma: %d/%d = %.0f %%  (target >= 90 "
      "%%)\n",
      library_ok, library, pct(library_ok, library));
  std::printf(
      "  outside effects never named as a library effect: %d/%d = %.0f %%  (target 100 %%)\n",
      outside_ok, outside, pct(outside_ok, outside));
  std::printf(
      "  coverage of the reported sigmas over %d fitted parameters: %.0f %% within 1 sigma (target "
      "60-75 %%), %.0f %% within 3 sigma (~99 %%)\n",
      params, pct(within1, params), pct(within3, params));
  std::printf(
      "  time per run (CPU, one thread): mean %.2f s, worst %.2f s  (target < 10 s; worst wall "
      "time %.2f s)\n",
      outcomes.empty() ? 0.0 : total_time / static_cast<double>(outcomes.size()), worst_time,
      worst_wall);
  std::printf("\nGap shrink (final position error of each replay, before -> after, m):\n");
  for (const auto& o : outcomes) {
    if (o.kind != CaseKind::kSingle && o.kind != CaseKind::kPair) continue;
    std::printf("  %-44s sensor %.4f -> %.4f   command %.4f -> %.4f\n", o.id.c_str(),
                o.position_before_m[0], o.position_after_m[0], o.position_before_m[1],
                o.position_after_m[1]);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The model-gap workflow on runs of the independent generator"};
  bool whole = false;
  bool subset = false;
  std::vector<std::string> ids;
  app.add_flag("--battery", whole, "run the whole independent battery");
  app.add_flag("--subset", subset, "with --battery: only the representative subset");
  app.add_option("--case", ids, "with --battery: only this case (repeatable)");
  if (const auto exit = swivel::cli::parse(app, argc, argv, "swivel-bench-model-gap")) {
    return *exit;
  }
  std::vector<BatteryCase> cases;
  if (!ids.empty()) {
    for (const auto& id : ids) {
      const BatteryCase* c = swivel::independent::find_case(id);
      if (c == nullptr) {
        std::fprintf(
            stderr,
            "swivel-bench-model-gap: no battery case '%s' (swivel-independent-run --list)\n",
            id.c_str());
        return swivel::cli::kUsageError;
      }
      cases.push_back(*c);
    }
  } else if (subset) {
    cases = swivel::independent::battery_subset();
  } else if (whole) {
    cases = swivel::independent::battery();
  } else {
    // Timing only: one 120 s run per robot.
    for (const char* id : {"docent/gyro_bias/large", "swpc4/steering_offset/large"}) {
      const BatteryCase* c = swivel::independent::find_case(id);
      if (c == nullptr) return 1;
      const battery::CaseOutcome o = battery::run_case(*c);
      std::printf("%-30s 120 s at 100 Hz: workflow %.2f s wall, %.2f s CPU; %s / %s\n", id,
                  o.wall_time_s, o.cpu_time_s, outcome_label(o, 0).c_str(),
                  outcome_label(o, 1).c_str());
    }
    return 0;
  }
  return run_battery(cases);
}
