// SPDX-License-Identifier: Apache-2.0
#include "calibration_mc_command.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/calibration/monte_carlo.hpp"
#include "swivel/stats/summary.hpp"

namespace swivel::calibration {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct NoiseLevel {
  std::string label;
  double position_m = 0.0;
  double yaw_rad = 0.0;
};

// "none" or "<pos>mm,<yaw>deg" (a '/' separator is accepted too).
NoiseLevel parse_noise(const std::string& text) {
  if (text == "none" || text == "0") return {"none", 0.0, 0.0};
  const auto sep = text.find_first_of(",/");
  const std::string pos = text.substr(0, sep);
  const std::string yaw = sep == std::string::npos ? "" : text.substr(sep + 1);
  const auto strip = [&](const std::string& s, const std::string& unit) {
    if (s.size() <= unit.size() || s.compare(s.size() - unit.size(), unit.size(), unit) != 0) {
      throw CLI::ValidationError("--noise", "'" + text +
                                                "': expected none or <pos>mm,<yaw>deg, e.g. "
                                                "0.1mm,0.05deg");
    }
    std::size_t used = 0;
    const std::string number = s.substr(0, s.size() - unit.size());
    double v = 0.0;
    try {
      v = std::stod(number, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != number.size() || !(v >= 0.0) || !std::isfinite(v)) {
      throw CLI::ValidationError("--noise",
                                 "'" + text + "': '" + number + "' is not a non-negative number");
    }
    return v;
  };
  const double pos_mm = strip(pos, "mm");
  const double yaw_deg = strip(yaw, "deg");
  char label[64];
  std::snprintf(label, sizeof label, "%g mm, %g deg (1-sigma)", pos_mm, yaw_deg);
  return {label, pos_mm * 1e-3, yaw_deg * kDeg};
}

// A bar redrawn in place on a terminal, or one plain line per 10 % otherwise.
class Progress {
 public:
  Progress(bool bar, std::string label) : bar_(bar), label_(std::move(label)) {}

  void update(std::size_t done, std::size_t total) {
    const std::size_t percent = total == 0 ? 100 : done * 100 / total;
    if (percent == last_percent_ && done != total) return;
    last_percent_ = percent;
    if (bar_) {
      constexpr std::size_t kWidth = 40;
      const std::size_t filled = percent * kWidth / 100;
      std::fprintf(stderr, "\r%s [%s%s] %3zu%% %zu/%zu", label_.c_str(),
                   std::string(filled, '#').c_str(), std::string(kWidth - filled, '.').c_str(),
                   percent, done, total);
      if (done == total) std::fprintf(stderr, "\n");
    } else if (percent % 10 == 0 && percent != last_line_percent_) {
      last_line_percent_ = percent;
      std::fprintf(stderr, "%s: %zu/%zu trials (%zu%%)\n", label_.c_str(), done, total, percent);
    }
    std::fflush(stderr);
  }

 private:
  bool bar_;
  std::string label_;
  std::size_t last_percent_ = 101;
  std::size_t last_line_percent_ = 101;
};

struct Settings {
  std::size_t trials = 10000;
  std::uint64_t seed = 1;
  std::vector<std::string> noise;
  bool progress = false;
};

void run(const Settings& s) {
  std::vector<NoiseLevel> levels;
  const std::vector<std::string> specs =
      s.noise.empty() ? std::vector<std::string>{"none", "0.1mm,0.05deg", "0.5mm,0.2deg"} : s.noise;
  levels.reserve(specs.size());
  for (const std::string& spec : specs) levels.push_back(parse_noise(spec));
  const bool bar = s.progress || isatty(fileno(stderr)) != 0;

  MonteCarloOptions base;
  base.trials = s.trials;
  base.seed = s.seed;
  std::printf("Table 3 reproduction: geometric calibration of an SWPC robot, Monte Carlo\n");
  std::printf(
      "robot: paper design, %zu modules; true x, y, d, r within +-%.0f %% of design, "
      "delta within +-%.0f deg\n",
      base.design.size(), base.relative_spread * 100.0, base.steering_offset_spread_rad / kDeg);
  std::printf(
      "motion: exact rigid rotation about the locked wheel, locked at %.1f and %.1f deg, "
      "%.1f deg counter-clockwise per run at %.2f rad/s, motion capture %.0f Hz\n",
      base.motion.locked_angles_meas_rad[0] / kDeg, base.motion.locked_angles_meas_rad[1] / kDeg,
      base.motion.rotation_rad / kDeg, base.motion.yaw_rate_radps, base.motion.sample_rate_hz);
  std::printf("trials: %zu per noise level, seed %llu; position error = |S_est - S_true|\n",
              s.trials, static_cast<unsigned long long>(s.seed));

  for (const NoiseLevel& level : levels) {
    MonteCarloOptions opt = base;
    opt.motion.position_noise_m = level.position_m;
    opt.motion.yaw_noise_rad = level.yaw_rad;
    auto progress = std::make_shared<Progress>(bar, "calibration-mc [" + level.label + "]");
    opt.progress = [progress](std::size_t done, std::size_t total) {
      progress->update(done, total);
    };
    const MonteCarloResult r = run_monte_carlo(opt);
    const bool noise_free = level.position_m == 0.0 && level.yaw_rad == 0.0;

    std::printf("\nmotion-capture noise: %s\n", level.label.c_str());
    std::printf("  %-14s %-12s %-12s %-12s %s\n", "parameter", "MAE", "+- std. err.", "max",
                "MAE (paper, Table 3)");
    // The standard error of each MAE over the trials (the independent draws).
    const auto standard_error = [&](double TrialErrors::*field, double scale) {
      if (r.trial_errors.empty()) return 0.0;
      std::vector<double> v;
      for (const TrialErrors& t : r.trial_errors) v.push_back(t.*field * scale);
      return stats::summarize(v).standard_error;
    };
    const auto row = [&](const char* name, double mae, double TrialErrors::*field, double scale,
                         double max, const char* paper) {
      std::printf("  %-14s %-12.4e %-12.2e %-12.4e %s\n", name, mae * scale,
                  standard_error(field, scale), max * scale, noise_free ? paper : "not reported");
    };
    row("position [mm]", r.mae_position_m, &TrialErrors::position_m, 1e3, r.max_position_m,
        "6.7818e-15");
    row("delta [deg]", r.mae_steering_offset_rad, &TrialErrors::steering_offset_rad, 1.0 / kDeg,
        r.max_steering_offset_rad, "2.7289e-16");
    row("d [mm]", r.mae_caster_offset_m, &TrialErrors::caster_offset_m, 1e3, r.max_caster_offset_m,
        "7.1324e-15");
    row("r [mm]", r.mae_wheel_radius_m, &TrialErrors::wheel_radius_m, 1e3, r.max_wheel_radius_m,
        "1.0411e-13");
    std::printf("  refused: %zu of %zu trials%s%s\n", r.refused, r.trials,
                r.refused > 0 ? "; first reason: " : "", r.first_refusal.c_str());
    if (!noise_free) {
      std::printf(
          "  reported 1-sigma covers the error within 3 sigma in %.2f %% of %zu "
          "(x, y, delta, d, r) errors\n",
          r.coverage_3sigma * 100.0, r.module_samples * 5);
    }
    const double per_module_us =
        r.module_samples > 0 ? r.calibrate_s / static_cast<double>(r.module_samples) * 1e6 : 0.0;
    std::printf("  wall time %.2f s (calibration alone %.2f s, %.1f us per module)\n", r.wall_s,
                r.calibrate_s, per_module_us);
  }
}

}  // namespace

CLI::App* add_calibration_mc_command(CLI::App& reproduce) {
  auto settings = std::make_shared<Settings>();
  CLI::App* cmd = reproduce.add_subcommand(
      "calibration-mc",
      "Monte Carlo of the geometric calibration (the paper's Table 3), then with motion-capture "
      "noise");
  cmd->add_option("--trials", settings->trials, "trials per noise level")
      ->default_val(10000)
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", settings->seed, "random seed")->default_val(1);
  cmd->add_option("--noise", settings->noise,
                  "motion-capture noise level, repeatable: none | <pos>mm,<yaw>deg "
                  "(default: none, 0.1mm,0.05deg, 0.5mm,0.2deg)");
  cmd->add_flag("--progress", settings->progress,
                "draw the progress bar even when stderr is not a terminal");
  cmd->callback([settings] { run(*settings); });
  return cmd;
}

}  // namespace swivel::calibration
