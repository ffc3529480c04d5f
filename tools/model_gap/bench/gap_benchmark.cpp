// SPDX-License-Identifier: Apache-2.0
// The model-gap workflow on runs it did not make, in two sets reported separately:
//
//   development  the independent battery (tests/independent_robot, 59 runs): its seeds were
//                used while the workflow's thresholds were tuned, so its figures are shown
//                for comparison and never judged;
//   validation   runs of the second robot generator (tests/second_robot) drawn from seed
//                ranges never used while developing (validation_set.hpp: clean
//                61136331-61136570, library 77438982-77439049, outside 97741474-97741485).
//                The pre-registered targets (validation_stats.hpp) are judged on this set;
//   first- to fifteenth-validation  the same cases from the earlier validation sets' seeds
//                (7340001..., 28880001..., 72548103..., 26341837..., 98462895..., 76076734...,
//                96537188..., 50642445..., 19798844..., 42696577..., 90474719..., 48877460...,
//                77376489..., 15340781..., 33893527...),
//                looked at after changes and are development data now: reported with the targets
//                beside them, never judged (only with --set first-validation etc.).
//
//   swivel-bench-model-gap [--set development|validation|first-validation|...|
//                                 fifteenth-validation|both] [--quick] [--jobs N]
//   swivel-bench-model-gap --case ID [--case ID ...]     development cases by id
//   swivel-bench-model-gap --repeat N                    each library effect's smoke case N
//                times over, the same robot, effect and rates with fresh noise and path: how
//                far the estimates scatter against the sigmas reported with them
//
// --quick: the battery's representative subset and a few runs of the second generator's
// smoke range (not the validation seeds); nothing is judged. Exit codes: 0 done and (with the
// full validation set) every target met, 1 a validation target missed, 2 usage error.
// Progress goes to stderr, the report to stdout.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "battery_scoring.hpp"
#include "swivel/cli/command_line.hpp"
#include "swivel/second/second_robot.hpp"
#include "swivel/second/validation_set.hpp"
#include "validation_stats.hpp"

namespace {

using namespace swivel::model_gap;
using battery::CaseOutcome;
using battery::RunKind;

// One run to make and analyse.
struct Job {
  std::string id;
  std::function<CaseOutcome()> run;
};

std::string outcome_label(const CaseOutcome& o, std::size_t q) {
  if (!o.error.empty()) return "error";
  if (o.verdict[q] == Verdict::kNamed) {
    std::vector<std::string> named = o.named[q];
    std::sort(named.begin(), named.end());
    std::string s;
    for (const auto& n : named) s += (s.empty() ? "" : "+") + n;
    return s;
  }
  return verdict_name(o.verdict[q]);
}

const char* kind_name(RunKind k) {
  switch (k) {
    case RunKind::kClean: return "clean";
    case RunKind::kLibrary: return "library";
    case RunKind::kOutside: return "outside";
  }
  return "?";
}

std::vector<CaseOutcome> run_all(const std::string& set, const std::vector<Job>& jobs,
                                 unsigned threads) {
  std::vector<CaseOutcome> out(jobs.size());
  std::atomic<std::size_t> next{0};
  std::size_t done = 0;
  std::mutex progress;
  const auto start = std::chrono::steady_clock::now();
  const auto worker = [&] {
    for (std::size_t i = next++; i < jobs.size(); i = next++) {
      out[i] = jobs[i].run();
      const std::lock_guard<std::mutex> lock(progress);
      ++done;
      const double s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr, "[%s %zu/%zu, %.0f s] %-34s %s\n", set.c_str(), done, jobs.size(), s,
                   jobs[i].id.c_str(), out[i].correct ? "ok" : "WRONG");
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  return out;
}

void print_runs(const std::vector<CaseOutcome>& outcomes) {
  std::printf("%-34s %-7s %-9s %5s  %-30s %-30s %s\n", "run", "kind", "robot", "Hz",
              "sensor to pose", "command to motion", "ok");
  for (const CaseOutcome& o : outcomes) {
    std::printf(
        "%-34s %-7s %-9s %5.0f  %-30s %-30s %s\n", o.id.c_str(), kind_name(o.kind), o.robot.c_str(),
        o.row_rate_hz, outcome_label(o, 0).c_str(), outcome_label(o, 1).c_str(),
        o.correct ? (o.kind == RunKind::kLibrary && !o.values_within_3_sigma ? "name ok, value off"
                                                                             : "yes")
                  : "NO");
    if (!o.correct) std::printf("    %s\n", o.problem.c_str());
    for (std::size_t q = 0; q < 2; ++q) {  // what the question saw, misfit channel included
      if (!o.undecided[q].empty() || (!o.correct && o.verdict[q] != Verdict::kNoSignificantGap))
        std::printf("    %s\n", o.summary[q].c_str());
    }
    if (!o.size_in_motion.value_or(true))
      std::printf("    friction-limited geometry: its size is not in the body's motion\n");
    if (o.kind == RunKind::kLibrary && o.servos_fighting.value_or(false)) {
      std::printf("    servos fighting their tyres: largest median servo error %.1f mrad\n",
                  o.driving_servo_error_rad.value_or(0.0) * 1e3);
    }
    if (o.kind == RunKind::kLibrary && o.fitted_steering_yield_rad && o.true_steering_yield_rad) {
      std::printf("    servos' yield: fitted %.1f mrad, the generator's d mu load / Kp %.1f mrad\n",
                  *o.fitted_steering_yield_rad * 1e3, *o.true_steering_yield_rad * 1e3);
    }
    for (const auto& p : o.params) {
      std::printf("    %s.%s: truth %.6g, fitted %.6g +- %.2g (%.1f sigma)\n", p.effect.c_str(),
                  p.key.c_str(), p.truth, p.value, p.sigma, p.deviation());
    }
    for (double z : o.effect_deviation_z) std::printf("    jointly %.1f sigma from the truth\n", z);
    for (std::size_t k = 0; k < o.calibrated.size(); ++k) {
      std::printf("    calibrated %s, %.1f sigma from the truth\n", o.calibrated[k].c_str(),
                  o.calibration_deviation_z[k]);
    }
  }
}

// False alarms among the clean runs, by tag (robot, row rate band, motion-capture mounting).
void print_breakdown(const std::vector<CaseOutcome>& outcomes) {
  std::map<std::string, validation::Proportion> by_tag;
  for (const CaseOutcome& o : outcomes) {
    if (o.kind != RunKind::kClean) continue;
    const bool alarm = !o.error.empty() || o.verdict[0] != Verdict::kNoSignificantGap ||
                       o.verdict[1] != Verdict::kNoSignificantGap;
    for (const auto& t : o.tags) by_tag[t].add(alarm);
  }
  if (by_tag.empty()) return;
  std::printf("\nFalse alarms among the clean runs, by group:\n");
  for (const auto& [tag, p] : by_tag) {
    const validation::Interval ci = p.interval();
    std::printf("  %-36s %3zu/%-3zu = %5.1f %%  [%.1f, %.1f]\n", tag.c_str(), p.hits, p.n,
                100.0 * p.value(), 100.0 * ci.low, 100.0 * ci.high);
  }
}

void print_figure(const char* name, const validation::Proportion& p) {
  if (p.n == 0) {
    std::printf("  %-52s no runs\n", name);
    return;
  }
  const validation::Interval ci = p.interval();
  std::printf("  %-52s %3zu/%-3zu = %5.1f %%  (95 %% Wilson [%.1f, %.1f])\n", name, p.hits, p.n,
              100.0 * p.value(), 100.0 * ci.low, 100.0 * ci.high);
}

// Library runs whose geometry the body's motion does not show the size of (one caster skidding
// on an over-actuated robot: swivel::second::GeometryFootprint) apart from the rest: not judged.
void print_friction_limited_split(const validation::SetFigures& f) {
  if (f.friction_limited_no_wrong_name.n == 0) return;
  print_figure("  size in the motion: named right, within 3 sigma", f.named_right_size_in_motion);
  print_figure("  friction-limited geometry: nothing not hidden named",
               f.friction_limited_no_wrong_name);
}

// The servos' yield the command question fitted against the generator's (fitted over true,
// caster runs), for the runs whose servos fight their tyres (where the run fixes it) and the
// rest (which may not reach it).
void print_steering_yield(const std::vector<CaseOutcome>& outcomes) {
  for (const bool fighting : {true, false}) {
    std::vector<double> ratio;
    for (const CaseOutcome& o : outcomes) {
      if (o.fitted_steering_yield_rad && o.true_steering_yield_rad &&
          o.servos_fighting.value_or(false) == fighting && *o.true_steering_yield_rad > 0.0)
        ratio.push_back(*o.fitted_steering_yield_rad / *o.true_steering_yield_rad);
    }
    if (ratio.empty()) continue;
    std::ranges::sort(ratio);
    const auto at = [&](double q) {
      return ratio[static_cast<std::size_t>(
          std::lround(q * static_cast<double>(ratio.size() - 1)))];
    };
    std::printf(
        "  servos' yield, fitted over the generator's (%s): median %.2f, "
        "10-90 %% %.2f-%.2f over %zu runs\n",
        fighting ? "servos fighting" : "not fighting", at(0.5), at(0.1), at(0.9), ratio.size());
  }
}

// The figures the targets are set on, for each drivetrain on its own: caster robots
// (steering servos, scrub while casters turn) are where the replays fall short; their runs
// named right are split by whether the servos fight their tyres.
void print_by_drivetrain(const std::vector<CaseOutcome>& outcomes) {
  for (const bool swpc : {false, true}) {
    std::vector<CaseOutcome> part;
    for (const CaseOutcome& o : outcomes)
      if (o.swpc == swpc) part.push_back(o);
    if (part.empty()) continue;
    const validation::SetFigures f = validation::figures(part);
    std::printf("\nFigures, %s robots only:\n", swpc ? "caster (swpc)" : "differential");
    print_figure("false alarms, either question (clean runs)", f.false_alarm);
    print_figure("in-library effects named right, within 3 sigma", f.named_right);
    print_friction_limited_split(f);
    if (f.named_right_servos_fighting.n + f.named_right_servos_not_fighting.n > 0) {
      print_figure("  servos fighting their tyres: named right", f.named_right_servos_fighting);
      print_figure("  servos not fighting: named right", f.named_right_servos_not_fighting);
    }
    if (swpc) print_steering_yield(part);
    print_figure("coverage: hidden parameters within 1 sigma", f.within_1_sigma);
    print_figure("coverage: hidden parameters within 3 sigma", f.within_3_sigma);
  }
}

// Under the null (clean runs) a candidate's significance is a normal deviate: the share of
// candidates at or above each z against the normal's upper tail, and the fits in the tail
// from 3 sigma (the normal expects one in 740) by name. Optionally every z with its expected
// normal quantile, effect and run, for a quantile plot (tools/lab/null_quantiles.gp).
void print_null_calibration(const validation::SetFigures& f, const std::string& quantiles_path) {
  const char* names[2] = {"sensor to pose", "command to motion"};
  std::FILE* out = quantiles_path.empty() ? nullptr : std::fopen(quantiles_path.c_str(), "w");
  if (!quantiles_path.empty() && out == nullptr) {
    std::fprintf(stderr, "swivel-bench-model-gap: cannot write %s\n", quantiles_path.c_str());
  }
  for (std::size_t q = 0; q < 2; ++q) {
    std::vector<battery::SingleFit> fits = f.clean_single_fits[q];
    if (fits.empty()) continue;
    std::ranges::sort(fits, {}, &battery::SingleFit::z);
    const auto n = static_cast<double>(fits.size());
    std::printf("    single candidates' z on clean runs, %s (%zu fits): share at or above",
                names[q], fits.size());
    for (double t : {1.0, 2.0, 3.0, 4.0, 5.0}) {
      const auto above = std::ranges::count_if(fits, [t](const auto& x) { return x.z >= t; });
      std::printf("  %.0f: %.2f %% (normal %.2f %%)", t, 100.0 * static_cast<double>(above) / n,
                  50.0 * std::erfc(t / std::sqrt(2.0)));
    }
    std::printf("\n");
    for (const auto& x : fits) {
      if (x.z >= 3.0)
        std::printf("      from 3 sigma: %-20s %5.2f  %s\n", x.effect.c_str(), x.z, x.run.c_str());
    }
    if (out == nullptr) continue;
    std::fprintf(out, "# %s: expected normal quantile, observed z, effect, run (clean runs)\n",
                 names[q]);
    for (std::size_t i = 0; i < fits.size(); ++i) {
      const double p = (static_cast<double>(i) + 0.5) / n;
      std::fprintf(out, "%.5f %.5f %s %s\n", validation::normal_quantile(p), fits[i].z,
                   fits[i].effect.c_str(), fits[i].run.c_str());
    }
    std::fprintf(out, "\n\n");
  }
  if (out != nullptr) std::fclose(out);
}

// The set's figures; the targets' verdicts when `judged`. Returns whether all were met.
bool report(const std::string& title, const std::vector<CaseOutcome>& outcomes, bool judged,
            const std::string& quantiles_path = "") {
  std::printf("\n==== %s: %zu runs ====\n", title.c_str(), outcomes.size());
  print_runs(outcomes);
  print_breakdown(outcomes);
  const validation::SetFigures f = validation::figures(outcomes);
  std::printf("\nFigures (%s):\n", title.c_str());
  print_figure("false alarms, either question (clean runs)", f.false_alarm);
  print_figure("  of which sensor to pose", f.sensor_false_alarm);
  print_figure("  of which command to motion", f.command_false_alarm);
  print_figure("noise larger than the model states (clean runs)", f.clean_noise_finding);
  print_figure("noise larger than the model states (library and outside runs)",
               f.effect_noise_finding);
  if (!f.clean_noise_ratios.empty()) {
    std::vector<double> r = f.clean_noise_ratios;
    std::sort(r.begin(), r.end());
    const auto at = [&r](double q) {
      return r[static_cast<std::size_t>(q * static_cast<double>(r.size() - 1))];
    };
    std::printf(
        "    clean runs' noise over the stated, largest channel: median %.2fx, 90 %% %.2fx, "
        "max %.2fx (reported from 2x)\n",
        at(0.5), at(0.9), r.back());
  }
  print_null_calibration(f, quantiles_path);
  print_figure("calibrated, not named (clean runs)", f.clean_calibrated);
  print_figure("calibrated values within 3 sigma of the truth", f.calibrated_within_3_sigma);
  print_figure("in-library effects named right, within 3 sigma", f.named_right);
  print_friction_limited_split(f);
  print_figure("outside effects: no wrong library name", f.outside_right);
  print_figure("undecided on clean runs (leaning, not named)", f.clean_undecided);
  print_figure("missed hidden effects the run leans towards", f.missed_undecided_hidden);
  print_figure("undecided leaning to an effect not hidden", f.undecided_not_hidden);
  print_figure("coverage: hidden parameters within 1 sigma", f.within_1_sigma);
  print_figure("coverage: hidden parameters within 3 sigma", f.within_3_sigma);
  std::printf("  workflow errors: %zu; CPU per run: mean %.2f s, worst %.2f s\n", f.errors,
              f.mean_cpu_s, f.worst_cpu_s);
  print_by_drivetrain(outcomes);
  const std::vector<validation::TargetResult> targets = validation::judge_targets(f);
  std::printf("\nTargets (pre-registered; %s):\n",
              judged ? "judged on this set" : "NOT judged on this set, shown for comparison");
  for (const auto& t : targets) {
    std::printf("  %-54s target %-12s measured %s: %s%s\n", t.name.c_str(), t.target.c_str(),
                t.measured.c_str(), t.met ? "met" : "MISSED",
                t.met && !t.met_by_whole_interval ? " (not by the whole interval)" : "");
  }
  return validation::all_met(targets);
}

std::vector<Job> development_jobs(const std::vector<swivel::independent::BatteryCase>& cases) {
  std::vector<Job> jobs;
  jobs.reserve(cases.size());
  for (const auto& c : cases) jobs.push_back({c.id, [c] { return battery::run_case(c); }});
  return jobs;
}

std::string rate_band(double hz) {
  if (hz < 40) return "rows 20-39 Hz";
  if (hz < 70) return "rows 40-69 Hz";
  return "rows 70-100 Hz";
}

std::vector<Job> validation_jobs(const std::vector<swivel::second::ValidationCase>& cases) {
  std::vector<Job> jobs;
  jobs.reserve(cases.size());
  for (const auto& c : cases) {
    jobs.push_back(
        {c.id, [c] {
           const swivel::second::GeneratedRun run = swivel::second::generate(c.spec);
           std::vector<battery::HiddenEffect> hidden;
           for (const auto& e : run.expected) hidden.push_back({e.effect, e.params});
           const RunKind kind = c.kind == swivel::second::CaseKind::kClean     ? RunKind::kClean
                                : c.kind == swivel::second::CaseKind::kLibrary ? RunKind::kLibrary
                                                                               : RunKind::kOutside;
           // A slippery floor may be called slip, the library's nearest law.
           CaseOutcome o = battery::analyse_and_score(c.id, kind, run.run_csv,
                                                      run.nominal_model_yaml, hidden, {"slip"});
           o.robot = c.spec.design;
           if (kind == RunKind::kLibrary) {
             if (const auto footprint = swivel::second::geometry_footprint(c.spec))
               o.size_in_motion = footprint->size_in_motion();
           }
           if (swivel::second::design(c.spec.design).drive == swivel::second::Drive::kSwpc) {
             o.driving_servo_error_rad = run.driving_servo_error_rad;
             o.servos_fighting =
                 run.driving_servo_error_rad >= swivel::second::kFightingServoErrorRad;
             std::vector<double> yield = swivel::second::friction_limit_servo_errors_rad(c.spec);
             std::ranges::sort(yield);
             if (!yield.empty()) o.true_steering_yield_rad = yield[yield.size() / 2];
           }
           const bool mounted = c.spec.truth.marker_x_m != 0.0 || c.spec.truth.marker_y_m != 0.0 ||
                                c.spec.truth.marker_yaw_rad != 0.0;
           o.tags = {"robot " + c.spec.design, rate_band(c.spec.row_rate_hz),
                     mounted ? "mocap marker offset and latency" : "mocap at the origin",
                     std::string("script ") + swivel::second::script_name(c.spec.script)};
           return o;
         }});
  }
  return jobs;
}

// An earlier validation set (development data now; `set` is e.g. "first-validation"):
// reported with the targets beside it.
void report_earlier_set(const std::string& set, unsigned jobs, const std::string& quantiles_path) {
  namespace sr = swivel::second;
  const auto cases = sr::validation_set(*sr::seed_ranges_named(set), sr::kValidationCleanRuns,
                                        sr::kValidationLibraryRuns, sr::kValidationOutsideRuns);
  const std::string name = set.substr(0, set.find('-')) + " validation set";
  const bool met = report(name +
                              " (second generator, seeds measured while developing: "
                              "development data, not judged)",
                          run_all(set, validation_jobs(cases), jobs), false, quantiles_path);
  std::printf("\nthe targets on the %s: %s (not judged)\n", name.c_str(),
              met ? "all met" : "missed");
}

// Each library effect's first smoke case (the smoke range: nothing of the validation sets),
// `repeats` times with seeds of its own, then per hidden parameter its scatter against its
// reported sigma.
void report_repeats(unsigned repeats, unsigned jobs) {
  namespace sr = swivel::second;
  std::vector<sr::ValidationCase> cases;
  const std::size_t effects = sr::library_case_effects().size();
  // The smoke range's first case of each effect, in the benchmark's order.
  for (const sr::ValidationCase& base : sr::validation_set(sr::kSmokeSeeds, 0, effects, 0)) {
    for (unsigned k = 1; k <= repeats; ++k) {
      sr::ValidationCase c = base;
      c.spec.seed = base.spec.seed * 1000 + k;  // 6001001...: no set's range
      c.id = base.id + "#" + std::to_string(k);
      cases.push_back(c);
    }
  }
  const std::vector<CaseOutcome> outcomes = run_all("repeats", validation_jobs(cases), jobs);
  std::printf("\n==== library effects, each case %u times with fresh noise and path ====\n",
              repeats);
  std::printf("%-24s %-9s %-44s %3s %12s %10s %10s %7s %6s %8s\n", "case", "robot", "parameter",
              "n", "truth", "scatter", "sigma", "ratio", "rms z", "within 1");
  for (std::size_t i = 0; i < effects; ++i) {
    const auto first = outcomes.begin() + static_cast<std::ptrdiff_t>(i * repeats);
    const std::vector<CaseOutcome> of(first, first + repeats);
    const sr::ValidationCase& c = cases[i * repeats];
    for (const validation::RepeatSpread& s : validation::repeat_spread(of)) {
      std::printf("%-24s %-9s %-44s %3zu %12.6g %10.2g %10.2g %7.2f %6.2f %7.0f%%\n",
                  c.id.substr(0, c.id.find('#')).c_str(), c.spec.design.c_str(),
                  (s.effect + "." + s.key).c_str(), s.n, s.truth, s.scatter, s.mean_sigma,
                  s.scatter_over_sigma(), s.rms_deviation, 100.0 * s.within_1_sigma.value());
    }
  }
}

// The earlier validation sets' names (development data now), as --set takes them.
std::vector<std::string> earlier_sets() {
  std::vector<std::string> out;
  for (const std::string& name : swivel::second::seed_set_names()) {
    if (name.ends_with("-validation")) out.push_back(name);
  }
  return out;
}

// Development cases by id (--case); a usage error for an unknown one.
int report_development_cases(const std::vector<std::string>& ids, unsigned jobs) {
  std::vector<swivel::independent::BatteryCase> cases;
  for (const auto& id : ids) {
    const auto* c = swivel::independent::find_case(id);
    if (c == nullptr) {
      std::fprintf(stderr,
                   "swivel-bench-model-gap: no battery case '%s' (swivel-independent-run --list)\n",
                   id.c_str());
      return swivel::cli::kUsageError;
    }
    cases.push_back(*c);
  }
  report("development cases", run_all("development", development_jobs(cases), jobs), false);
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"The model-gap workflow on development and validation runs, with targets"};
  std::string set = "both";
  bool quick = false;
  bool battery_flag = false;
  bool subset = false;
  unsigned jobs = std::max(1U, std::thread::hardware_concurrency());
  std::vector<std::string> ids;
  const std::vector<std::string> earlier = earlier_sets();
  std::vector<std::string> sets = {"development", "validation", "both"};
  sets.insert(sets.end(), earlier.begin(), earlier.end());
  app.add_option("--set", set,
                 "development, validation, first- to fifteenth-validation (earlier sets), or both")
      ->check(CLI::IsMember(sets));
  app.add_flag("--quick", quick,
               "smoke test: the battery's subset and a few smoke-range runs; nothing judged");
  app.add_option("--jobs", jobs, "parallel runs (default: the hardware's threads)")
      ->check(CLI::Range(1U, 64U));
  app.add_flag("--battery", battery_flag, "the development set only (as --set development)");
  app.add_flag("--subset", subset, "with --battery: the representative subset only");
  app.add_option("--case", ids, "a development case by id (repeatable)");
  unsigned repeats = 0;
  app.add_option("--repeat", repeats,
                 "each library effect's smoke case this many times with fresh noise: the "
                 "estimates' scatter against their sigmas")
      ->check(CLI::Range(2U, 1000U));
  std::string quantiles_path;
  app.add_option("--null-quantiles", quantiles_path,
                 "write the clean validation runs' candidate z with their normal quantiles here "
                 "(tools/lab/null_quantiles.gp plots them)");
  if (const auto exit = swivel::cli::parse(app, argc, argv, "swivel-bench-model-gap")) {
    return *exit;
  }
  if (battery_flag) set = "development";
  if (subset) quick = true;

  if (repeats > 0) {
    report_repeats(repeats, jobs);
    return 0;
  }
  if (!ids.empty()) return report_development_cases(ids, jobs);

  std::printf("swivel-bench-model-gap --set %s%s --jobs %u\n", set.c_str(), quick ? " --quick" : "",
              jobs);
  namespace sr = swivel::second;
  if (std::find(earlier.begin(), earlier.end(), set) != earlier.end()) {
    report_earlier_set(set, jobs, quantiles_path);
    return 0;
  }
  if (set != "validation") {
    const auto cases =
        quick ? swivel::independent::battery_subset() : swivel::independent::battery();
    report(quick ? "development (battery subset)"
                 : "development (independent battery, used while tuning)",
           run_all("development", development_jobs(cases), jobs), false);
  }
  if (set == "development") return 0;
  const auto cases =
      quick ? sr::validation_set(sr::kSmokeSeeds, 6, 4, 1)
            : sr::validation_set(sr::kValidationSeeds, sr::kValidationCleanRuns,
                                 sr::kValidationLibraryRuns, sr::kValidationOutsideRuns);
  const bool met = report(quick ? "smoke (second generator, smoke seeds: not the validation set)"
                                : "validation (second generator, fresh seeds)",
                          run_all(quick ? "smoke" : "validation", validation_jobs(cases), jobs),
                          !quick, quantiles_path);
  if (quick) return 0;
  std::printf("\nvalidation targets: %s\n", met ? "all met" : "MISSED (exit 1)");
  return met ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swivel-bench-model-gap: %s\n", e.what());
    return 1;
  }
}
