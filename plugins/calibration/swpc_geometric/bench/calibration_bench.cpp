// SPDX-License-Identifier: Apache-2.0
// Timing of the calibration: one full robot calibration (all modules), and the Monte Carlo
// per trial (generation + calibration).
#include <benchmark/benchmark.h>

#include <random>

#include "swivel/calibration/calibration_motion.hpp"
#include "swivel/calibration/monte_carlo.hpp"
#include "swivel/calibration/swpc_calibration.hpp"

namespace {

using swivel::calibration::CalibrationInput;
using swivel::calibration::CalibrationMotionOptions;

void calibrate_robot(benchmark::State& state) {
  const auto truth = swivel::calibration::paper_design_modules();
  CalibrationMotionOptions opt;
  opt.position_noise_m = 1e-4;
  opt.yaw_noise_rad = 1e-3;
  std::mt19937_64 rng(1);
  CalibrationInput input;
  std::string error;
  if (!swivel::calibration::generate_calibration_motion(truth, opt, rng, input, error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  for ([[maybe_unused]] auto iteration : state) {
    auto res = swivel::calibration::calibrate(input);
    benchmark::DoNotOptimize(res);
  }
  // Each module: 2 runs of ~315 samples each (90 deg at 0.5 rad/s, 100 Hz).
  state.counters["modules"] = static_cast<double>(truth.size());
  // Seconds per calibrated module (a rate inverted), printed by Google Benchmark in s.
  state.counters["s_per_module"] =
      benchmark::Counter(static_cast<double>(state.iterations() * truth.size()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(calibrate_robot)->Unit(benchmark::kMicrosecond);

void monte_carlo_trial(benchmark::State& state) {
  swivel::calibration::MonteCarloOptions opt;
  opt.trials = 100;
  for ([[maybe_unused]] auto iteration : state) {
    auto res = swivel::calibration::run_monte_carlo(opt);
    benchmark::DoNotOptimize(res);
  }
  state.SetItemsProcessed(state.iterations() * 100);
}
BENCHMARK(monte_carlo_trial)->Unit(benchmark::kMillisecond);

}  // namespace
