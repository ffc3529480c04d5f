// SPDX-License-Identifier: Apache-2.0
// swivel-lab reproduce docent: the docent paper's straight-run comparison (docs/methods.md §2) in
// simulation, printed in the paper's table layout with the paper's values beside ours, plus
// results.json and two gnuplot PNGs.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "docent_experiment.hpp"
#include "gnuplot.hpp"
#include "swivel/pose_math.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/shipped_config.hpp"
#include "swivel/stats/summary.hpp"

namespace swivel::lab {
namespace {

namespace fs = std::filesystem;

constexpr double kCmPerM = 100.0;
constexpr std::size_t kPaperMethods = 3;  // E/G, LCAKF, LCALSM
constexpr std::size_t kPaperRuns = 5;

// The paper's published values (docs/methods.md §2), indexed [scenario][method] and
// [scenario][run][method]; method order E/G, LCAKF, LCALSM.
constexpr std::array<std::array<double, kPaperMethods>, 2> kPaperMaxCm{{
    {13.44, 13.89, 5.35},
    {7.38, 7.33, 2.30},
}};
constexpr std::array<std::array<std::array<double, kPaperMethods>, kPaperRuns>, 2> kPaperMeanCm{{
    {{{3.77, 1.80, 1.50},
      {14.29, 12.83, 12.21},
      {9.94, 8.49, 6.01},
      {1.37, 1.38, 1.34},
      {0.91, 0.21, 0.18}}},
    {{{0.94, 0.67, 0.54},
      {3.89, 1.80, 1.76},
      {2.67, 2.58, 2.31},
      {1.93, 0.79, 0.75},
      {4.01, 4.06, 2.85}}},
}};
// The paper's stated claims: max-error reduction of LCALSM vs E/G per scenario, and how much
// LCALSM's mean-error reduction beats LCAKF's, on average.
constexpr std::array<double, 2> kPaperMaxReductionPct{60.19, 68.83};
constexpr double kPaperAdvantageOverLcakfPct = 4.85;

struct DocentCommandOptions {
  // The repository's model for a build-tree binary, the installed one otherwise.
  std::string model_file = shipped_config_file("robots/docent.yaml").string();
  std::size_t runs = 5;
  bool runs_given = false;
  std::uint64_t seed = 1;
  std::string out_dir = "docent_reproduction";
  bool short_mode = false;
};

constexpr std::array<DocentMethod, kDocentMethodCount> kMethods{
    DocentMethod::kEg, DocentMethod::kLcakf, DocentMethod::kLcalsmPaper,
    DocentMethod::kLcalsmHeading, DocentMethod::kEkf};

std::size_t idx(DocentMethod m) { return static_cast<std::size_t>(m); }

std::string fixed(double v, int precision = 2) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << v;
  return s.str();
}

// Shortest general form: 4096 stays "4096", 2796.8 stays "2796.8".
std::string general(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string pad(const std::string& text, std::size_t width) {
  return text.size() >= width ? text : std::string(width - text.size(), ' ') + text;
}

std::string left(const std::string& text, std::size_t width) {
  return text.size() >= width ? text : text + std::string(width - text.size(), ' ');
}

double mean(const std::vector<double>& v) { return stats::summarize(v).mean; }

// Sample standard deviation (n - 1), 0 for fewer than two values.
double sample_std(const std::vector<double>& v) { return stats::summarize(v).standard_deviation; }

// A sample standard deviation with its standard error, s / sqrt(2 (n - 1)) (normal data).
stats::Estimate std_estimate(const std::vector<double>& v) {
  const double s = sample_std(v);
  return {s, v.size() > 1 ? s / std::sqrt(2.0 * static_cast<double>(v.size() - 1)) : 0.0};
}

// Per scenario and method, over runs: each with its standard error.
struct MethodSummary {
  stats::Estimate mean_max_m;
  stats::Estimate mean_mean_m;
  stats::Estimate std_of_run_means_m;
  stats::Estimate mean_within_std_m;
};

struct ScenarioSummary {
  std::array<MethodSummary, kDocentMethodCount> method{};
  // Max-error reduction vs E/G: 1 - mean(max) / mean(max of E/G), paired by run (fraction).
  std::array<stats::Estimate, kDocentMethodCount> max_reduction_vs_eg{};
  // Mean-error reduction vs E/G, per run, averaged over runs (fraction).
  std::array<stats::Estimate, kDocentMethodCount> mean_reduction_vs_eg{};
  // LCALSM's per-run mean-error reduction minus LCAKF's, averaged over runs (fraction).
  stats::Estimate lcalsm_minus_lcakf;
};

ScenarioSummary summarize(const DocentScenarioResult& sr) {
  ScenarioSummary out;
  std::vector<double> eg_maxes;
  for (const DocentRunResult& r : sr.runs) {
    eg_maxes.push_back(r.stats[idx(DocentMethod::kEg)].max_error_m);
  }
  std::array<std::vector<double>, kDocentMethodCount> reductions;
  for (DocentMethod m : kMethods) {
    std::vector<double> maxes;
    std::vector<double> means;
    std::vector<double> within;
    for (const DocentRunResult& r : sr.runs) {
      const DocentMethodStats& s = r.stats[idx(m)];
      maxes.push_back(s.max_error_m);
      means.push_back(s.mean_error_m);
      within.push_back(s.std_error_m);
      const double eg = r.stats[idx(DocentMethod::kEg)].mean_error_m;
      reductions[idx(m)].push_back(eg > 0.0 ? (eg - s.mean_error_m) / eg : 0.0);
    }
    out.method[idx(m)] = MethodSummary{stats::summarize(maxes).mean_estimate(),
                                       stats::summarize(means).mean_estimate(), std_estimate(means),
                                       stats::summarize(within).mean_estimate()};
    out.mean_reduction_vs_eg[idx(m)] = stats::summarize(reductions[idx(m)]).mean_estimate();
    const stats::Estimate change = stats::paired_relative_change(eg_maxes, maxes);
    out.max_reduction_vs_eg[idx(m)] = {-change.value, change.standard_error};
  }
  std::vector<double> difference;
  for (std::size_t r = 0; r < sr.runs.size(); ++r) {
    difference.push_back(reductions[idx(DocentMethod::kLcalsmPaper)][r] -
                         reductions[idx(DocentMethod::kLcakf)][r]);
  }
  out.lcalsm_minus_lcakf = stats::summarize(difference).mean_estimate();
  return out;
}

// The paper's derived figures, recomputed from its tables with our definitions.
struct PaperDerived {
  std::array<double, kPaperMethods> mean_reduction_vs_eg{};
  std::array<double, kPaperMethods> std_of_run_means_cm{};
};

PaperDerived paper_derived(std::size_t scenario) {
  PaperDerived d;
  for (std::size_t m = 0; m < kPaperMethods; ++m) {
    std::vector<double> means;
    std::vector<double> reductions;
    for (const auto& run : kPaperMeanCm[scenario]) {
      means.push_back(run[m]);
      reductions.push_back((run[0] - run[m]) / run[0]);
    }
    d.mean_reduction_vs_eg[m] = mean(reductions);
    d.std_of_run_means_cm[m] = sample_std(means);
  }
  return d;
}

double reduction(double reference, double value) {
  return reference > 0.0 ? (reference - value) / reference : 0.0;
}

std::vector<std::string> assumptions(const RobotModel& nominal, const DocentExperimentConfig& c) {
  const DocentErrorModel& e = c.errors;
  const DocentDriveProfile& d = c.drive;
  const auto samples = static_cast<int>(std::lround(8.0 / c.sample_spacing_m));
  // Each line is one sentence, its literals wrapped: no comma is missing.
  // NOLINTBEGIN(bugprone-suspicious-missing-comma)
  return {
      "robot: " + nominal.name + " (nominal model " + nominal.source_file + "): wheel radii " +
          fixed(nominal.differential.wheel_radius_left_m, 3) + " m, track " +
          fixed(nominal.differential.track_width_m, 2) +
          " m; odometry and estimators use only "
          "this nominal model",
      "corridor 8 m x 10 m; S1 (0,3) -> (8,3), S2 (0,6) -> (8,6); " + std::to_string(c.runs) +
          " runs each, seed " + std::to_string(c.seed),
      "driving: still for " + fixed(d.still_before_s, 1) + " s (gyro running), then ramp at " +
          fixed(d.accel_mps2, 2) + " m/s^2 to " + fixed(d.cruise_speed_mps, 2) + " m/s, brake at " +
          fixed(d.accel_mps2, 2) +
          " m/s^2 to stop at x = 8 m; a line "
          "follower on the TRUE pose keeps the robot on the corridor line (stand-in for the "
          "paper's guided straight runs), so truth is straight and the errors are the "
          "estimators'",
      "true robot drawn per run (unknown to the estimators): gyro bias N(0, " +
          fixed(e.gyro_bias_sigma_radps * kDegPerRad, 3) +
          " deg/s) (residual after a start-up "
          "bias calibration), gyro scale 1 + N(0, " +
          fixed(e.gyro_scale_sigma * 100.0, 2) + " %), each wheel radius nominal x (1 + U(-" +
          fixed(e.wheel_radius_error_max * 100.0, 2) + " %, +" +
          fixed(e.wheel_radius_error_max * 100.0, 2) + " %))",
      "sensors: wheel encoders quantized at " +
          general(nominal.sensors.wheel_encoder_counts_per_rev) + " counts/rev; gyro white noise " +
          fixed(e.gyro_noise_radps, 4) +
          " rad/s per sample (a MEMS yaw gyro of the R1050K's class; values assumed, not "
          "from a datasheet); random wheel slip " +
          fixed(e.wheel_slip_std * 100.0, 2) + " % (1-sigma, Gauss-Markov, " +
          fixed(e.slip_correlation_time_s, 1) +
          " s); no "
          "motion capture",
      "loop rate " + fixed(d.rate_hz, 0) +
          " Hz; error = distance between estimate and truth "
          "where the truth crosses every " +
          fixed(c.sample_spacing_m, 2) + " m (" + std::to_string(samples) + " samples per run)",
      "methods: E/G (gyro heading, eq. (1)-(7), nominal gyro scale and bias); LCAKF (kalman "
      "mode lcakf, default noise); LCALSM (lsm mode paper, k = 10, a point every 0.02 m, "
      "real-time output); extras marked *: LCALSM-HA* = lsm mode heading_aligned (variant), "
      "EKF* = kalman mode ekf (pose + gyro bias, no pose fixes)",
      "the simulator has no position-dependent effects: S1 and S2 differ only by their random "
      "draws",
  };
  // NOLINTEND(bugprone-suspicious-missing-comma)
}

// Our cells carry "value+-standard error" (entries over runs) or the value alone (one run).
constexpr std::size_t kOurs = 13;
constexpr std::size_t kPaper = 7;

std::string with_se(const stats::Estimate& e, double scale) {
  return fixed(e.value * scale) + "+-" + fixed(e.standard_error * scale);
}

void print_header_row(std::ostream& os, const std::string& first, std::size_t first_width) {
  os << left(first, first_width);
  for (std::size_t m = 0; m < kPaperMethods; ++m) {
    os << pad(docent_method_label(kMethods[m]), kOurs) << pad("paper", kPaper);
  }
  os << " |" << pad(docent_method_label(DocentMethod::kLcalsmHeading), kOurs + 1)
     << pad(docent_method_label(DocentMethod::kEkf), kOurs) << '\n';
}

// Our values in cm (with their standard errors when `se`), the paper's beside them.
void print_value_row(std::ostream& os, const std::string& first, std::size_t first_width,
                     const std::array<stats::Estimate, kDocentMethodCount>& ours_m, bool se,
                     const std::array<std::optional<double>, kPaperMethods>& paper_cm) {
  const auto cell = [&](DocentMethod m) {
    const stats::Estimate& e = ours_m[idx(m)];
    return se ? with_se(e, kCmPerM) : fixed(e.value * kCmPerM);
  };
  os << left(first, first_width);
  for (std::size_t m = 0; m < kPaperMethods; ++m) {
    os << pad(cell(kMethods[m]), kOurs) << pad(paper_cm[m] ? fixed(*paper_cm[m]) : "-", kPaper);
  }
  os << " |" << pad(cell(DocentMethod::kLcalsmHeading), kOurs + 1)
     << pad(cell(DocentMethod::kEkf), kOurs) << '\n';
}

void print_tables(std::ostream& os, const std::vector<DocentScenarioResult>& results,
                  const std::vector<ScenarioSummary>& summaries,
                  const std::vector<std::string>& assumption_lines) {
  const std::size_t runs = results.front().runs.size();
  os << "swivel-lab reproduce docent: docs/methods.md §2 (E/G, LCAKF, LCALSM) in simulation\n"
     << "Our values are measured in simulation, as mean+-standard error over the runs where "
        "they are over runs; columns labelled \"paper\" are the paper's published values.\n\n"
        "Assumptions:\n";
  for (const std::string& a : assumption_lines) os << "  - " << a << '\n';

  os << "\nRuns drawn (true robot):\n"
     << "scenario run  gyro_bias_deg/s  gyro_scale  r_left_scale  r_right_scale  duration_s"
        "  EKF_bias_deg/s\n";
  for (const DocentScenarioResult& sr : results) {
    for (std::size_t r = 0; r < sr.runs.size(); ++r) {
      const DocentRunResult& run = sr.runs[r];
      os << left(sr.scenario.name, 9) << pad(std::to_string(r + 1), 3)
         << pad(fixed(run.draw.gyro_bias_radps * kDegPerRad, 4), 17)
         << pad(fixed(run.draw.gyro_scale, 4), 12)
         << pad(fixed(run.draw.wheel_radius_scale_left, 5), 14)
         << pad(fixed(run.draw.wheel_radius_scale_right, 5), 15)
         << pad(fixed(run.duration_s, 1), 12) << pad(fixed(run.ekf_bias_radps * kDegPerRad, 4), 16)
         << '\n';
    }
  }

  const auto column = [&](std::size_t s, stats::Estimate MethodSummary::*field) {
    std::array<stats::Estimate, kDocentMethodCount> out{};
    for (DocentMethod m : kMethods) out[idx(m)] = summaries[s].method[idx(m)].*field;
    return out;
  };

  os << "\nTable 1. Maximum error (cm, mean+-standard error over " << runs
     << " runs; paper: mean of 5)\n";
  print_header_row(os, "scenario", 9);
  for (std::size_t s = 0; s < results.size(); ++s) {
    std::array<std::optional<double>, kPaperMethods> paper{};
    for (std::size_t m = 0; m < kPaperMethods; ++m) paper[m] = kPaperMaxCm[s][m];
    print_value_row(os, results[s].scenario.name, 9, column(s, &MethodSummary::mean_max_m), true,
                    paper);
  }

  for (std::size_t s = 0; s < results.size(); ++s) {
    const DocentScenarioResult& sr = results[s];
    os << "\nTable 2. Mean error per run (cm), " << sr.scenario.name << '\n';
    print_header_row(os, "run", 9);
    for (std::size_t r = 0; r < sr.runs.size(); ++r) {
      std::array<stats::Estimate, kDocentMethodCount> ours{};
      for (DocentMethod m : kMethods) ours[idx(m)] = {sr.runs[r].stats[idx(m)].mean_error_m, 0.0};
      std::array<std::optional<double>, kPaperMethods> paper{};
      if (r < kPaperRuns) {
        for (std::size_t m = 0; m < kPaperMethods; ++m) paper[m] = kPaperMeanCm[s][r][m];
      }
      print_value_row(os, std::to_string(r + 1), 9, ours, false, paper);
    }
    std::array<std::optional<double>, kPaperMethods> paper{};
    for (std::size_t m = 0; m < kPaperMethods; ++m) {
      double sum = 0.0;
      for (const auto& run : kPaperMeanCm[s]) sum += run[m];
      paper[m] = sum / static_cast<double>(kPaperRuns);
    }
    print_value_row(os, "mean", 9, column(s, &MethodSummary::mean_mean_m), true, paper);
  }

  constexpr std::size_t kRatio = 15;
  os << "\nTable 3. Reduction ratios (%), mean+-standard error over runs\n"
     << left("", 46) << pad("S1", kRatio) << pad("paper", 8) << pad("S2", kRatio) << pad("paper", 8)
     << '\n';
  auto ratio_row = [&](const std::string& label, auto ours_fn, auto paper_fn) {
    os << left(label, 46);
    for (std::size_t s = 0; s < results.size(); ++s) {
      os << pad(with_se(ours_fn(s), 100.0), kRatio);
      const std::optional<double> p = paper_fn(s);
      os << pad(p ? fixed(*p) : "-", 8);
    }
    os << '\n';
  };
  auto max_red = [&](DocentMethod m) {
    return [&, m](std::size_t s) { return summaries[s].max_reduction_vs_eg[idx(m)]; };
  };
  auto paper_max_red = [](std::size_t m) {
    return [m](std::size_t s) -> std::optional<double> {
      return 100.0 * reduction(kPaperMaxCm[s][0], kPaperMaxCm[s][m]);
    };
  };
  auto none = [](std::size_t) -> std::optional<double> { return std::nullopt; };
  ratio_row("max-error reduction vs E/G: LCALSM", max_red(DocentMethod::kLcalsmPaper),
            [](std::size_t s) -> std::optional<double> { return kPaperMaxReductionPct[s]; });
  ratio_row("max-error reduction vs E/G: LCAKF", max_red(DocentMethod::kLcakf), paper_max_red(1));
  ratio_row("max-error reduction vs E/G: LCALSM-HA*", max_red(DocentMethod::kLcalsmHeading), none);
  ratio_row("max-error reduction vs E/G: EKF*", max_red(DocentMethod::kEkf), none);
  auto mean_red = [&](DocentMethod m) {
    return [&, m](std::size_t s) { return summaries[s].mean_reduction_vs_eg[idx(m)]; };
  };
  auto paper_mean_red = [](std::size_t m) {
    return [m](std::size_t s) -> std::optional<double> {
      return 100.0 * paper_derived(s).mean_reduction_vs_eg[m];
    };
  };
  ratio_row("mean-error reduction vs E/G: LCAKF", mean_red(DocentMethod::kLcakf),
            paper_mean_red(1));
  ratio_row("mean-error reduction vs E/G: LCALSM", mean_red(DocentMethod::kLcalsmPaper),
            paper_mean_red(2));
  ratio_row("mean-error reduction vs E/G: LCALSM-HA*", mean_red(DocentMethod::kLcalsmHeading),
            none);
  ratio_row("mean-error reduction vs E/G: EKF*", mean_red(DocentMethod::kEkf), none);
  ratio_row(
      "LCALSM's mean-error reduction minus LCAKF's",
      [&](std::size_t s) { return summaries[s].lcalsm_minus_lcakf; },
      [](std::size_t s) -> std::optional<double> {
        const PaperDerived d = paper_derived(s);
        return 100.0 * (d.mean_reduction_vs_eg[2] - d.mean_reduction_vs_eg[1]);
      });
  os << "  mean-error reductions are per run (E/G - method)/E/G, averaged over runs; the paper "
        "column is recomputed\n  from its Table 2 with that definition. The paper states "
     << fixed(kPaperAdvantageOverLcakfPct)
     << " % on average for the last row without a "
        "definition.\n  Max-error reductions use Table 1; their standard error pairs each "
        "run's maxima (first order).\n";

  os << "\nTable 4. Error standard deviation (cm)\n";
  print_header_row(os, "scenario statistic", 30);
  for (std::size_t s = 0; s < results.size(); ++s) {
    const PaperDerived d = paper_derived(s);
    std::array<std::optional<double>, kPaperMethods> paper{};
    for (std::size_t m = 0; m < kPaperMethods; ++m) paper[m] = d.std_of_run_means_cm[m];
    print_value_row(os, results[s].scenario.name + " across runs", 30,
                    column(s, &MethodSummary::std_of_run_means_m), true, paper);
    print_value_row(os, results[s].scenario.name + " within runs", 30,
                    column(s, &MethodSummary::mean_within_std_m), true, {});
  }
  os << "  across runs: sample std of the per-run mean errors (paper: recomputed from its "
        "Table 2), +- s/sqrt(2(n-1));\n  within runs: std of the errors along each run, "
        "averaged over runs (the paper gives no per-sample data).\n";

  os << "\nReading:\n";
  for (std::size_t s = 0; s < results.size(); ++s) {
    const auto& m = summaries[s].method;
    os << "  " << results[s].scenario.name << ": LCALSM (paper mode) max error "
       << with_se(m[idx(DocentMethod::kLcalsmPaper)].mean_max_m, kCmPerM) << " cm vs E/G "
       << with_se(m[idx(DocentMethod::kEg)].mean_max_m, kCmPerM) << " cm ("
       << with_se(max_red(DocentMethod::kLcalsmPaper)(s), 100.0) << " % reduction; paper "
       << fixed(kPaperMaxReductionPct[s]) << " %); heading_aligned variant "
       << with_se(m[idx(DocentMethod::kLcalsmHeading)].mean_max_m, kCmPerM) << " cm ("
       << with_se(max_red(DocentMethod::kLcalsmHeading)(s), 100.0) << " %)\n";
  }
  os << "  A k-point line fit over a short window (k = 10 points, 0.2 m) cannot see a drift "
        "that is smooth over metres;\n  the heading_aligned variant projects onto the line the "
        "robot set out on and removes lateral drift on straight\n  runs. No method corrects the "
        "along-track error from the wheel radius mismatch.\n";
}

nlohmann::json to_json(const RobotModel& nominal, const DocentExperimentConfig& c,
                       const std::vector<DocentScenarioResult>& results,
                       const std::vector<ScenarioSummary>& summaries,
                       const std::vector<std::string>& assumption_lines) {
  using nlohmann::json;
  json j;
  j["tool"] = "swivel-lab reproduce docent";
  j["paper"] = "docs/methods.md section 2 (LCALSM docent robot)";
  j["robot_model"] = nominal.source_file;
  j["config"] = {
      {"runs", c.runs},
      {"seed", c.seed},
      {"sample_spacing_m", c.sample_spacing_m},
      {"errors",
       {{"gyro_bias_sigma_radps", c.errors.gyro_bias_sigma_radps},
        {"gyro_scale_sigma", c.errors.gyro_scale_sigma},
        {"gyro_noise_radps", c.errors.gyro_noise_radps},
        {"wheel_radius_error_max", c.errors.wheel_radius_error_max},
        {"wheel_slip_std", c.errors.wheel_slip_std},
        {"slip_correlation_time_s", c.errors.slip_correlation_time_s},
        {"wheel_encoder_counts_per_rev", nominal.sensors.wheel_encoder_counts_per_rev}}},
      {"drive",
       {{"rate_hz", c.drive.rate_hz},
        {"still_before_s", c.drive.still_before_s},
        {"cruise_speed_mps", c.drive.cruise_speed_mps},
        {"accel_mps2", c.drive.accel_mps2},
        {"min_speed_mps", c.drive.min_speed_mps},
        {"lateral_gain_per_m2", c.drive.lateral_gain_per_m2},
        {"yaw_gain_per_s", c.drive.yaw_gain_per_s}}},
  };
  j["assumptions"] = assumption_lines;
  j["methods"] = json::array();
  for (DocentMethod m : kMethods) {
    j["methods"].push_back({{"key", docent_method_key(m)}, {"label", docent_method_label(m)}});
  }
  j["scenarios"] = json::array();
  for (std::size_t s = 0; s < results.size(); ++s) {
    const DocentScenarioResult& sr = results[s];
    json js;
    js["name"] = sr.scenario.name;
    js["start_m"] = {sr.scenario.start_x_m, sr.scenario.line_y_m};
    js["end_m"] = {sr.scenario.end_x_m, sr.scenario.line_y_m};
    js["runs"] = json::array();
    for (const DocentRunResult& r : sr.runs) {
      json jr;
      jr["draw"] = {{"seed", r.draw.seed},
                    {"gyro_bias_radps", r.draw.gyro_bias_radps},
                    {"gyro_scale", r.draw.gyro_scale},
                    {"wheel_radius_scale_left", r.draw.wheel_radius_scale_left},
                    {"wheel_radius_scale_right", r.draw.wheel_radius_scale_right}};
      jr["duration_s"] = r.duration_s;
      jr["true_end_m"] = {r.true_end.x_m, r.true_end.y_m};
      jr["ekf_bias_radps"] = r.ekf_bias_radps;
      jr["sample_x_m"] = r.sample_x_m;
      for (DocentMethod m : kMethods) {
        const DocentMethodStats& st = r.stats[idx(m)];
        jr["methods"][docent_method_key(m)] = {{"max_error_m", st.max_error_m},
                                               {"mean_error_m", st.mean_error_m},
                                               {"std_error_m", st.std_error_m},
                                               {"eg_input_mismatch_m", st.eg_input_mismatch_m},
                                               {"errors_m", r.errors_m[idx(m)]}};
      }
      js["runs"].push_back(jr);
    }
    for (DocentMethod m : kMethods) {
      const MethodSummary& ms = summaries[s].method[idx(m)];
      const stats::Estimate& max_red = summaries[s].max_reduction_vs_eg[idx(m)];
      const stats::Estimate& mean_red = summaries[s].mean_reduction_vs_eg[idx(m)];
      js["summary"][docent_method_key(m)] = {
          {"mean_max_error_m", ms.mean_max_m.value},
          {"mean_max_error_standard_error_m", ms.mean_max_m.standard_error},
          {"mean_mean_error_m", ms.mean_mean_m.value},
          {"mean_mean_error_standard_error_m", ms.mean_mean_m.standard_error},
          {"std_of_run_mean_errors_m", ms.std_of_run_means_m.value},
          {"std_of_run_mean_errors_standard_error_m", ms.std_of_run_means_m.standard_error},
          {"mean_within_run_std_m", ms.mean_within_std_m.value},
          {"mean_within_run_std_standard_error_m", ms.mean_within_std_m.standard_error},
          {"max_error_reduction_vs_eg", max_red.value},
          {"max_error_reduction_vs_eg_standard_error", max_red.standard_error},
          {"mean_error_reduction_vs_eg", mean_red.value},
          {"mean_error_reduction_vs_eg_standard_error", mean_red.standard_error}};
    }
    js["summary"]["lcalsm_minus_lcakf_mean_error_reduction"] = {
        {"mean", summaries[s].lcalsm_minus_lcakf.value},
        {"standard_error", summaries[s].lcalsm_minus_lcakf.standard_error}};
    const PaperDerived d = paper_derived(s);
    json jp;
    for (std::size_t m = 0; m < kPaperMethods; ++m) {
      const char* key = docent_method_key(kMethods[m]);
      std::vector<double> per_run;
      for (const auto& run : kPaperMeanCm[s]) per_run.push_back(run[m] / kCmPerM);
      jp[key] = {{"mean_max_error_m", kPaperMaxCm[s][m] / kCmPerM},
                 {"mean_error_per_run_m", per_run},
                 {"mean_error_reduction_vs_eg_from_table", d.mean_reduction_vs_eg[m]},
                 {"std_of_run_mean_errors_m_from_table", d.std_of_run_means_cm[m] / kCmPerM}};
    }
    jp["stated_max_error_reduction_lcalsm_vs_eg"] = kPaperMaxReductionPct[s] / 100.0;
    js["paper"] = jp;
    j["scenarios"].push_back(js);
  }
  j["paper_stated_mean_reduction_advantage_over_lcakf"] = kPaperAdvantageOverLcakfPct / 100.0;
  return j;
}

void write_plot_data(const fs::path& dir, const std::vector<DocentScenarioResult>& results) {
  for (const DocentScenarioResult& sr : results) {
    std::ofstream traj(dir / ("trajectory_" + sr.scenario.name + ".dat"));
    traj << "# run 1 of " << sr.scenario.name << ": t_s, then x_m y_m of truth";
    for (DocentMethod m : kMethods) traj << ", " << docent_method_key(m);
    traj << '\n' << std::setprecision(9);
    for (const DocentTracePoint& p : sr.runs.front().trace) {
      traj << p.t_s << ' ' << p.truth.x_m << ' ' << p.truth.y_m;
      for (DocentMethod m : kMethods)
        traj << ' ' << p.estimate[idx(m)].x_m << ' ' << p.estimate[idx(m)].y_m;
      traj << '\n';
    }
    std::ofstream err(dir / ("errors_" + sr.scenario.name + ".dat"));
    err << "# " << sr.scenario.name << ": true x_m, then error (cm) per method, mean over "
        << sr.runs.size() << " runs:";
    for (DocentMethod m : kMethods) err << ' ' << docent_method_key(m);
    err << '\n' << std::setprecision(6);
    const std::size_t n = sr.runs.front().sample_x_m.size();
    for (std::size_t i = 0; i < n; ++i) {
      double x = 0.0;
      for (const DocentRunResult& r : sr.runs) x += r.sample_x_m[i];
      err << x / static_cast<double>(sr.runs.size());
      for (DocentMethod m : kMethods) {
        double e = 0.0;
        for (const DocentRunResult& r : sr.runs) e += r.errors_m[idx(m)][i];
        err << ' ' << kCmPerM * e / static_cast<double>(sr.runs.size());
      }
      err << '\n';
    }
  }
}

// Writes plots.gp next to the data and runs gnuplot on it.
void write_plots(const fs::path& dir, const std::vector<DocentScenarioResult>& results) {
  write_plot_data(dir, results);
  const char* styles[] = {"lc rgb '#d62728' dt 1", "lc rgb '#ff7f0e' dt 2", "lc rgb '#1f77b4' dt 1",
                          "lc rgb '#2ca02c' dt 4", "lc rgb '#9467bd' dt 3"};
  std::ostringstream g;
  g << "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
       "  set terminal pngcairo size 1200,1400 font ',10'\n} else {\n"
       "  set terminal png size 1200,1400\n}\n"
    << "set output " << gnuplot_quote(dir / "trajectories.png") << "\n"
    << "set multiplot layout 3,1 title 'Docent corridor runs (run 1 of each scenario)'\n"
       "set key outside right\nset grid\n"
       "set title 'Corridor 8 m x 10 m: truth and estimates'\n"
       "set xlabel 'x (m)'\nset ylabel 'y (m)'\nset xrange [-0.5:8.5]\nset yrange [0:10]\n"
       "set size ratio -1\n"
       "set object 1 rect from 0,0 to 8,10 fs empty border lc rgb 'black' lw 2\n"
       "set arrow 1 from 0,3 to 8,3 nohead dt 3 lc rgb 'gray'\n"
       "set arrow 2 from 0,6 to 8,6 nohead dt 3 lc rgb 'gray'\n"
       "set label 1 'S1' at 8.1,3\nset label 2 'S2' at 8.1,6\n";
  g << "plot";
  for (std::size_t s = 0; s < results.size(); ++s) {
    const std::string file =
        gnuplot_quote(dir / ("trajectory_" + results[s].scenario.name + ".dat"));
    g << (s == 0 ? " " : ", ") << file << " using 2:3 with lines lw 2 lc rgb 'black' title '"
      << results[s].scenario.name << " truth'";
    g << ", " << file << " using 4:5 with lines " << styles[0] << " title '"
      << results[s].scenario.name << " E/G'";
  }
  g << "\nunset object 1\nunset arrow 1\nunset arrow 2\nunset label 1\nunset label 2\n"
       "set size noratio\nset autoscale y\n";
  // E/G drawn wide underneath: the methods fed from it often coincide with it.
  for (const DocentScenarioResult& sr : results) {
    const std::string file = gnuplot_quote(dir / ("trajectory_" + sr.scenario.name + ".dat"));
    g << "set title '" << sr.scenario.name
      << ": lateral offset from the line y = " << fixed(sr.scenario.line_y_m, 1)
      << " m'\nset ylabel 'y - line (cm)'\nplot " << file << " using 2:(100*($3-"
      << sr.scenario.line_y_m << ")) with lines lw 2 lc rgb 'black' title 'truth'";
    for (DocentMethod m : kMethods) {
      const std::size_t col = 4 + 2 * idx(m);
      g << ", " << file << " using " << col << ":(100*($" << col + 1 << "-" << sr.scenario.line_y_m
        << ")) with lines lw " << (m == DocentMethod::kEg ? 4 : 1.5) << ' ' << styles[idx(m)]
        << " title '" << docent_method_label(m) << "'";
    }
    g << '\n';
  }
  g << "unset multiplot\n";

  g << "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
       "  set terminal pngcairo size 1200,900 font ',10'\n} else {\n"
       "  set terminal png size 1200,900\n}\n"
    << "set output " << gnuplot_quote(dir / "errors.png") << "\n"
    << "set multiplot layout 2,1 title 'Position error over distance (mean over runs)'\n"
       "set xrange [0:8]\nset autoscale y\nset yrange [0:*]\n"
       "set xlabel 'distance along the corridor (m)'\nset ylabel 'error (cm)'\n";
  for (const DocentScenarioResult& sr : results) {
    const std::string file = gnuplot_quote(dir / ("errors_" + sr.scenario.name + ".dat"));
    g << "set title '" << sr.scenario.name << " (" << sr.runs.size() << " runs)'\nplot";
    for (DocentMethod m : kMethods) {
      g << (idx(m) == 0 ? " " : ", ") << file << " using ($1-" << sr.scenario.start_x_m
        << "):" << idx(m) + 2 << " with linespoints pt 7 ps 0.4 lw "
        << (m == DocentMethod::kEg ? 4 : 1.5) << ' ' << styles[idx(m)] << " title '"
        << docent_method_label(m) << "'";
    }
    g << '\n';
  }
  g << "unset multiplot\n";

  const fs::path script = dir / "plots.gp";
  std::ofstream(script) << g.str();
  run_gnuplot(script, "the tables and results.json");
}

int run_reproduce_docent(const DocentCommandOptions& o) {
  RobotModel nominal = load_robot_model(o.model_file);
  DocentExperimentConfig config;
  config.seed = o.seed;
  config.runs = o.runs_given ? o.runs : (o.short_mode ? 2 : 5);
  config.sample_spacing_m = o.short_mode ? 0.5 : 0.1;
  // The true gyro is as noisy as the nominal model says; its bias and scale are drawn.
  config.errors.gyro_noise_radps = nominal.sensors.gyro.noise_rad_s;

  const std::vector<DocentScenarioResult> results = run_docent_experiment(nominal, config);
  std::vector<ScenarioSummary> summaries;
  summaries.reserve(results.size());
  for (const DocentScenarioResult& sr : results) summaries.push_back(summarize(sr));
  const std::vector<std::string> lines = assumptions(nominal, config);

  const fs::path dir(o.out_dir);
  fs::create_directories(dir);
  std::ostringstream tables;
  print_tables(tables, results, summaries, lines);
  std::cout << tables.str();
  std::ofstream(dir / "tables.txt") << tables.str();
  std::ofstream(dir / "results.json")
      << to_json(nominal, config, results, summaries, lines).dump(2) << '\n';
  write_plots(dir, results);
  std::cout << "\nwrote " << (dir / "results.json").string() << ", "
            << (dir / "trajectories.png").string() << ", " << (dir / "errors.png").string() << ", "
            << (dir / "tables.txt").string() << '\n';
  return 0;
}

}  // namespace

void add_reproduce_docent_command(CLI::App& reproduce, int& exit_code) {
  auto options = std::make_shared<DocentCommandOptions>();
  CLI::App* cmd = reproduce.add_subcommand(
      "docent",
      "docs/methods.md §2: E/G, LCAKF and LCALSM (plus the heading_aligned variant and the EKF) on "
      "the simulated docent robot, scenarios S1 and S2, compared with the paper's tables");
  cmd->add_option("--model", options->model_file, "nominal docent robot model (YAML)")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  cmd->add_option_function<std::size_t>(
         "--runs",
         [options](const std::size_t& n) {
           options->runs = n;
           options->runs_given = true;
         },
         "runs per scenario (default 5; 2 with --short)")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--seed", options->seed, "random seed of the per-run draws")
      ->capture_default_str();
  cmd->add_option("--out", options->out_dir,
                  "output directory (results.json, trajectories.png, errors.png, tables.txt)")
      ->capture_default_str();
  cmd->add_flag("--short", options->short_mode,
                "2 runs per scenario, errors sampled every 0.5 m instead of 0.1 m (test suite)");
  cmd->callback([options, &exit_code]() { exit_code = run_reproduce_docent(*options); });
}

}  // namespace swivel::lab
