// SPDX-License-Identifier: Apache-2.0
#include "swivel/calibration/monte_carlo.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

namespace swivel::calibration {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

std::vector<SwpcModuleParams> paper_design_modules() {
  const double xy[4][2] = {{0.215, 0.125}, {0.215, -0.125}, {-0.215, -0.125}, {-0.215, 0.125}};
  std::vector<SwpcModuleParams> modules;
  for (const auto& p : xy) {
    SwpcModuleParams m;
    m.x_m = p[0];
    m.y_m = p[1];
    m.steering_offset_rad = 0.0;
    m.caster_offset_m = 0.020;
    m.wheel_radius_m = 0.055;
    modules.push_back(m);
  }
  return modules;
}

std::vector<SwpcModuleParams> paper_table4_modules() {
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double x_mm[] = {216.16, 216.52, -216.22, -216.67};
  const double y_mm[] = {126.96, -124.74, -125.26, 126.47};
  const double delta_deg[] = {0.6349, 1.5247, 0.9764, 1.2154};
  const double d_mm[] = {20.3907, 20.2223, 20.3055, 20.2897};
  const double r_mm[] = {54.3960, 54.7413, 55.9731, 55.6682};
  std::vector<SwpcModuleParams> modules(4);
  for (std::size_t i = 0; i < 4; ++i) {
    modules[i] = {x_mm[i] * 1e-3, y_mm[i] * 1e-3, delta_deg[i] * kDeg, d_mm[i] * 1e-3,
                  r_mm[i] * 1e-3};
  }
  return modules;
}

MonteCarloResult run_monte_carlo(const MonteCarloOptions& options) {
  const Clock::time_point start = Clock::now();
  MonteCarloResult res;
  res.trials = options.trials;
  std::size_t covered = 0;
  std::size_t coverage_total = 0;
  CalibrationInput input;
  std::vector<SwpcModuleParams> truth(options.design.size());
  CalibrationMotionOptions motion = options.motion;

  for (std::size_t trial = 0; trial < options.trials; ++trial) {
    // One stream per trial: a trial's data do not depend on how many ran before it.
    std::seed_seq seq{static_cast<std::uint32_t>(options.seed),
                      static_cast<std::uint32_t>(options.seed >> 32U),
                      static_cast<std::uint32_t>(trial)};
    std::mt19937_64 rng(seq);
    std::uniform_real_distribution<double> rel(1.0 - options.relative_spread,
                                               1.0 + options.relative_spread);
    std::uniform_real_distribution<double> offset(-options.steering_offset_spread_rad,
                                                  options.steering_offset_spread_rad);
    std::uniform_real_distribution<double> place(-2.0, 2.0);
    std::uniform_real_distribution<double> heading(-std::numbers::pi, std::numbers::pi);
    for (std::size_t m = 0; m < truth.size(); ++m) {
      const SwpcModuleParams& d = options.design[m];
      truth[m].x_m = d.x_m * rel(rng);
      truth[m].y_m = d.y_m * rel(rng);
      truth[m].caster_offset_m = d.caster_offset_m * rel(rng);
      truth[m].wheel_radius_m = d.wheel_radius_m * rel(rng);
      truth[m].steering_offset_rad = d.steering_offset_rad + offset(rng);
    }
    motion.start_pose = {place(rng), place(rng), heading(rng)};

    std::string error;
    if (!generate_calibration_motion(truth, motion, rng, input, error)) {
      if (res.refused++ == 0) res.first_refusal = error;
      if (options.progress) options.progress(trial + 1, options.trials);
      continue;
    }
    const Clock::time_point cal_start = Clock::now();
    const CalibrationResult cal = calibrate(input, options.calibration);
    res.calibrate_s += seconds_since(cal_start);
    if (!cal.ok()) {
      if (res.refused++ == 0) res.first_refusal = cal.reason();
    } else {
      TrialErrors errors;
      const auto modules = static_cast<double>(truth.size());
      for (std::size_t m = 0; m < truth.size(); ++m) {
        const SwpcModuleParams& est = cal.modules[m].params;
        const SwpcModuleSigma& sig = cal.modules[m].sigma;
        const double ex = est.x_m - truth[m].x_m;
        const double ey = est.y_m - truth[m].y_m;
        const double ed = wrap_pi(est.steering_offset_rad - truth[m].steering_offset_rad);
        const double ec = est.caster_offset_m - truth[m].caster_offset_m;
        const double er = est.wheel_radius_m - truth[m].wheel_radius_m;
        const double ep = std::hypot(ex, ey);
        res.mae_position_m += ep;
        res.mae_steering_offset_rad += std::abs(ed);
        res.mae_caster_offset_m += std::abs(ec);
        res.mae_wheel_radius_m += std::abs(er);
        errors.position_m += ep / modules;
        errors.steering_offset_rad += std::abs(ed) / modules;
        errors.caster_offset_m += std::abs(ec) / modules;
        errors.wheel_radius_m += std::abs(er) / modules;
        res.max_position_m = std::max(res.max_position_m, ep);
        res.max_steering_offset_rad = std::max(res.max_steering_offset_rad, std::abs(ed));
        res.max_caster_offset_m = std::max(res.max_caster_offset_m, std::abs(ec));
        res.max_wheel_radius_m = std::max(res.max_wheel_radius_m, std::abs(er));
        const double errs[5] = {ex, ey, ed, ec, er};
        const double sigs[5] = {sig.x_m, sig.y_m, sig.steering_offset_rad, sig.caster_offset_m,
                                sig.wheel_radius_m};
        for (int i = 0; i < 5; ++i) {
          covered += std::abs(errs[i]) <= 3.0 * sigs[i] ? 1U : 0U;
          ++coverage_total;
        }
        ++res.module_samples;
      }
      res.trial_errors.push_back(errors);
    }
    if (options.progress) options.progress(trial + 1, options.trials);
  }
  if (res.module_samples > 0) {
    const auto count = static_cast<double>(res.module_samples);
    res.mae_position_m /= count;
    res.mae_steering_offset_rad /= count;
    res.mae_caster_offset_m /= count;
    res.mae_wheel_radius_m /= count;
  }
  if (coverage_total > 0) {
    res.coverage_3sigma = static_cast<double>(covered) / static_cast<double>(coverage_total);
  }
  res.wall_s = seconds_since(start);
  return res;
}

}  // namespace swivel::calibration
