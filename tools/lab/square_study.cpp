// SPDX-License-Identifier: Apache-2.0
#include "square_study.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>

#include "swivel/calibration/calibration_io.hpp"
#include "swivel/pose_math.hpp"

namespace swivel::lab {
namespace {

// Seed streams, so that no two draws share a seed.
enum Stream : std::uint64_t {
  kNominalRuns = 1,
  kExactRuns = 2,
  kCalibrations = 3,
  kCalibratedRuns = 4
};

// SplitMix64's finaliser: neighbouring inputs give unrelated outputs.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30U)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27U)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31U);
}

std::uint64_t derive_seed(std::uint64_t base, std::uint64_t stream, std::uint64_t index) {
  return mix(mix(mix(base) ^ stream) ^ index);
}

TrackedModel track(const RobotModel& truth, const RobotModel& model,
                   const SquareStudyOptions& options, std::uint64_t stream, bool traced) {
  TrackedModel out;
  out.model = model;
  for (const bool ccw : {false, true}) {
    for (int j = 0; j < options.runs_per_direction; ++j) {
      SquareRunOptions ro = options.run;
      ro.counter_clockwise = ccw;
      const auto index = static_cast<std::uint64_t>(j) * 2 + (ccw ? 1 : 0);
      ro.seed = derive_seed(options.seed, stream, index);
      if (!traced || j >= options.traced_runs) ro.trace_every = 0;
      const SquareRunResult r = run_square(truth, model, ro);
      if (!r.finished) throw std::runtime_error("square run did not finish within its time limit");
      out.runs.push_back(
          {ccw, j, ro.seed, r.position_error_m, r.heading_error_rad / kRadPerDeg, r.trace});
    }
  }
  return out;
}

}  // namespace

SquareStudy run_square_study(const RobotModel& nominal, const RobotModel& truth,
                             const SquareStudyOptions& options, const StudyProgress& progress) {
  if (options.calibration_seeds < 1 || options.runs_per_direction < 1 || options.jobs < 1) {
    throw std::invalid_argument("square study: need at least one calibration, run and job");
  }
  SquareStudy study;
  const int calibrations = options.calibrated_model ? 1 : options.calibration_seeds;
  study.calibrated.resize(static_cast<std::size_t>(calibrations));

  // Task 0 tracks the design values, 1 the true ones, 2 + k calibrated model k.
  const int tasks = 2 + calibrations;
  const auto task = [&](int t) -> std::string {
    if (t == 0) {
      study.nominal = track(truth, nominal, options, kNominalRuns, true);
      return "design values tracked";
    }
    if (t == 1) {
      study.exact = track(truth, truth, options, kExactRuns, true);
      return "true values tracked";
    }
    const auto k = static_cast<std::size_t>(t - 2);
    CalibratedModel& c = study.calibrated[k];
    RobotModel model;
    if (options.calibrated_model) {
      model = *options.calibrated_model;
    } else {
      calibration::SimulatedProcedureOptions co = options.calibration;
      co.sim.seed = derive_seed(options.seed, kCalibrations, k);
      const calibration::SimulatedCalibration sc =
          calibration::run_simulated_calibration(nominal, truth, co);
      if (!sc.result.ok()) {
        throw std::runtime_error("simulated calibration " + std::to_string(k + 1) +
                                 " was refused: " + sc.result.reason());
      }
      model = calibration::calibrated_model(nominal, sc.result);
      c.calibration_seed = co.sim.seed;
      c.calibration_duration_s = sc.duration_s;
    }
    c.tracked = track(truth, model, options, kCalibratedRuns + k, k == 0);
    return options.calibrated_model ? "given model tracked"
                                    : "calibration " + std::to_string(k + 1) + " of " +
                                          std::to_string(calibrations) + " done and tracked";
  };

  std::atomic<int> next{0};
  std::mutex report;
  int done = 0;
  std::exception_ptr failure;
  const auto worker = [&]() {
    for (int t = next++; t < tasks; t = next++) {
      try {
        const std::string what = task(t);
        const std::lock_guard<std::mutex> lock(report);
        ++done;
        if (progress) progress(done, tasks, what);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(report);
        if (!failure) failure = std::current_exception();
        next = tasks;  // the others stop after their current task
      }
    }
  };
  std::vector<std::thread> threads;
  for (int j = 1; j < std::min(options.jobs, tasks); ++j) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  if (failure) std::rethrow_exception(failure);
  return study;
}

}  // namespace swivel::lab
