// SPDX-License-Identifier: Apache-2.0
// swivel-lab reproduce square: the tracking test of docs/methods.md §1 (Table 5, Fig. 13) with its
// statistics. The simulated robot's true parameters are the paper's calibrated values
// (Table 4); it follows a 2.5 m square on its own odometry with the design values, with
// the true values (the bound), and with the values each of K simulated calibrations (the
// daemon's procedure) recovers, or the values of a calibrated model file given with
// --calibrated-model (e.g. the one swiveld wrote).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "square_plots.hpp"
#include "square_study.hpp"
#include "square_summary.hpp"
#include "swivel/calibration/monte_carlo.hpp"
#include "swivel/pose_math.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::lab {
namespace {

namespace fs = std::filesystem;
constexpr double kSideM = 2.5;

// Table 5 of the paper, for the side-by-side print only.
constexpr double kPaperPosNominalM = 0.4674;
constexpr double kPaperPosCalibratedM = 0.1655;
constexpr double kPaperHeadNominalDeg = 9.6721;
constexpr double kPaperHeadCalibratedDeg = 1.9200;
constexpr double kPaperPosChange = -0.6460;
constexpr double kPaperHeadChange = -0.8015;

struct SquareOptions {
  int calibrations = 20;
  int runs = 20;
  std::uint64_t seed = 1;
  std::string out_dir = "square";
  bool short_mode = false;
  double slip_std = 0.01;
  double scrub_std = 0.005;
  double substep_s = 0.001;
  double rotation_deg = 300.0;
  int jobs = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  std::string calibrated_model;  // "" = calibrate the simulated robot here
};

RobotModel design_model() {
  RobotModel m;
  m.name = "swpc4";
  m.drivetrain = DrivetrainKind::kSwpc;
  m.modules = calibration::paper_design_modules();
  return m;
}

RobotModel table4_model() {
  RobotModel m = design_model();
  m.modules = calibration::paper_table4_modules();
  return m;
}

std::string pm(const stats::Estimate& e, int decimals, double scale = 1.0) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f +- %.*f", decimals, e.value * scale, decimals,
                e.standard_error * scale);
  return buf;
}

nlohmann::json estimate_json(const stats::Estimate& e, double scale = 1.0) {
  return {{"mean", e.value * scale}, {"standard_error", e.standard_error * scale}};
}

nlohmann::json spread_json(const stats::Summary& s, std::size_t worse) {
  return {{"min", 100.0 * s.min},
          {"median", 100.0 * s.median},
          {"max", 100.0 * s.max},
          {"worse_than_design", worse},
          {"count", s.count}};
}

nlohmann::json runs_json(const TrackedModel& t) {
  nlohmann::json runs = nlohmann::json::array();
  for (const TrackedRun& r : t.runs) {
    runs.push_back({{"direction", r.counter_clockwise ? "ccw" : "cw"},
                    {"run", r.index + 1},
                    {"seed", r.seed},
                    {"position_error_m", r.position_error_m},
                    {"heading_error_deg", r.heading_error_deg}});
  }
  return runs;
}

void print_results(const SquareStudy& study, const SquareSummary& s, int runs, bool given) {
  const std::size_t k = study.calibrated.size();
  if (!given) {
    std::printf("\ncalibration accuracy, rms over %zu calibrations (recovered - true)\n", k);
    std::printf("  %-6s %-10s %-12s %-10s %-10s\n", "module", "pos [mm]", "delta [deg]", "d [mm]",
                "r [mm]");
    for (std::size_t i = 0; i < s.accuracy.size(); ++i) {
      const ModuleAccuracy& a = s.accuracy[i];
      std::printf("  %-6zu %-10.4f %-12.4f %-10.4f %-10.4f\n", i + 1, a.position_mm,
                  a.steering_offset_deg, a.caster_offset_mm, a.wheel_radius_mm);
    }
  }
  std::printf(
      "\nend-pose mean absolute error, mean +- standard error over %s, %d runs per "
      "direction each\n",
      given ? "the given model's runs" : (std::to_string(k) + " calibrations").c_str(), runs);
  std::printf("  %-14s %-19s %-19s %-15s | %-7s %-8s %-10s %s\n", "", "design values", "calibrated",
              "change [%]", "paper:", "design", "calibrated", "change");
  std::printf("  %-14s %-19s %-19s %-15s | %-7s %-8.4f %-10.4f %+.2f %%\n", "position [m]",
              pm(s.nominal.position_m, 4).c_str(), pm(s.calibrated.position_m, 4).c_str(),
              pm(s.position_change, 1, 100.0).c_str(), "", kPaperPosNominalM, kPaperPosCalibratedM,
              100.0 * kPaperPosChange);
  std::printf("  %-14s %-19s %-19s %-15s | %-7s %-8.4f %-10.4f %+.2f %%\n", "heading [deg]",
              pm(s.nominal.heading_deg, 3).c_str(), pm(s.calibrated.heading_deg, 3).c_str(),
              pm(s.heading_change, 1, 100.0).c_str(), "", kPaperHeadNominalDeg,
              kPaperHeadCalibratedDeg, 100.0 * kPaperHeadChange);
  std::printf("  true values as the model (Table 4: the bound for any calibration):\n");
  std::printf("  %-14s %-19s %-19s %-15s\n", "position [m]", "", pm(s.exact.position_m, 4).c_str(),
              pm(s.exact_position_change, 1, 100.0).c_str());
  std::printf("  %-14s %-19s %-19s %-15s\n", "heading [deg]", "",
              pm(s.exact.heading_deg, 3).c_str(), pm(s.exact_heading_change, 1, 100.0).c_str());
  if (k > 1) {
    std::printf("\nchange per calibration seed (%zu seeds)\n", k);
    std::printf("  %-14s %-9s %-9s %-9s %s\n", "", "min", "median", "max",
                "worse than design values");
    std::printf("  %-14s %-+9.1f %-+9.1f %-+9.1f %zu of %zu\n", "position [%]",
                100.0 * s.position_spread.min, 100.0 * s.position_spread.median,
                100.0 * s.position_spread.max, s.position_worse, k);
    std::printf("  %-14s %-+9.1f %-+9.1f %-+9.1f %zu of %zu\n", "heading [%]",
                100.0 * s.heading_spread.min, 100.0 * s.heading_spread.median,
                100.0 * s.heading_spread.max, s.heading_worse, k);
  }
  std::printf(
      "\nnotes: +- is one standard error: over the calibrated models (each tracked --runs times "
      "per direction), and over the runs for the design and true values. The true values' row "
      "is what slip, scrub, sensor noise and the follower leave; the gap to it is what the "
      "calibrated parameters' errors cost, mostly through the steering offsets (see "
      "tools/lab/CALIBRATION.md). The paper reports one calibration and 4 runs per direction, "
      "and neither their scatter nor its motion-capture noise.\n");
}

int run_square_reproduction(const SquareOptions& o) {
  const auto started = std::chrono::steady_clock::now();
  const RobotModel nominal = design_model();
  const RobotModel truth = table4_model();

  SquareStudyOptions so;
  so.calibration_seeds = o.short_mode ? 2 : o.calibrations;
  so.runs_per_direction = o.short_mode ? 2 : o.runs;
  so.seed = o.seed;
  so.jobs = o.jobs;
  so.run.side_m = kSideM;
  so.run.laps = o.short_mode ? 1 : 2;
  so.run.nonsystematic.wheel_slip_std = o.slip_std;
  so.run.nonsystematic.lateral_scrub_std = o.scrub_std;
  so.run.substep_s = o.substep_s;
  so.calibration.procedure.rotation_rad = o.rotation_deg * kRadPerDeg;
  if (!o.calibrated_model.empty()) {
    RobotModel given = load_robot_model(o.calibrated_model);
    if (given.drivetrain != DrivetrainKind::kSwpc || given.modules.size() != truth.modules.size()) {
      std::fprintf(stderr, "reproduce square: %s: expected an swpc model with %zu modules\n",
                   o.calibrated_model.c_str(), truth.modules.size());
      return 2;
    }
    so.calibrated_model = std::move(given);
  }
  const bool given = so.calibrated_model.has_value();
  const calibration::ProcedureOptions& procedure = so.calibration.procedure;

  std::printf("Table 5 reproduction: square tracking on odometry, design values vs calibrated\n");
  std::printf("true robot: the paper's calibrated values (Table 4); nominal: design values\n");
  if (given) {
    std::printf("calibrated: %s\n", o.calibrated_model.c_str());
  } else {
    std::printf(
        "calibrated: %d simulated calibrations, the daemon's procedure (per module 2 runs of %.0f "
        "deg at %.1f rad/s, %s-driven free wheels), motion capture %.1f mm / %.2f deg at %.0f "
        "Hz, 4096-count encoders\n",
        so.calibration_seeds, procedure.rotation_rad / kRadPerDeg, procedure.yaw_rate_radps,
        procedure.wheel_drive == calibration::WheelDrive::kTorque ? "torque" : "velocity",
        truth.sensors.motion_capture.position_noise_m * 1e3,
        truth.sensors.motion_capture.yaw_noise_rad / kRadPerDeg,
        truth.sensors.motion_capture.rate_hz);
  }
  std::printf(
      "path: %.1f m square, %d lap(s), CW and CCW, %d run(s) each per model, 0.2 m/s, 90 deg "
      "turns in place; non-systematic: wheel slip %.1f %%, lateral scrub %.1f %% (1-sigma, 0.5 s "
      "correlation), gyro/encoder/motion-capture noise of the model; integration step %.0f ms; "
      "seed %llu\n",
      kSideM, so.run.laps, so.runs_per_direction, o.slip_std * 100.0, o.scrub_std * 100.0,
      o.substep_s * 1e3, static_cast<unsigned long long>(o.seed));
  std::fflush(stdout);

  const SquareStudy study =
      run_square_study(nominal, truth, so, [&](int done, int total, const std::string& what) {
        const double s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        std::fprintf(stderr, "reproduce square: [%d/%d] %s (%.1f s)\n", done, total, what.c_str(),
                     s);
      });
  const SquareSummary s = summarize_square(study, truth);
  print_results(study, s, so.runs_per_direction, given);

  const fs::path dir(o.out_dir);
  fs::create_directories(dir);
  nlohmann::json j;
  j["experiment"] = "docs/methods.md §1 Table 5: square tracking on odometry";
  j["settings"] = {{"side_m", kSideM},
                   {"laps", so.run.laps},
                   {"runs_per_direction", so.runs_per_direction},
                   {"calibration_seeds", given ? 0 : so.calibration_seeds},
                   {"speed_mps", 0.2},
                   {"seed", o.seed},
                   {"wheel_slip_std", o.slip_std},
                   {"lateral_scrub_std", o.scrub_std},
                   {"substep_s", o.substep_s},
                   {"calibration_rotation_deg", procedure.rotation_rad / kRadPerDeg},
                   {"short", o.short_mode}};
  if (given) j["calibrated_model"] = o.calibrated_model;
  j["measured"] = {
      {"position_mae_m",
       {{"nominal", s.nominal.position_m.value},
        {"calibrated", s.calibrated.position_m.value},
        {"exact", s.exact.position_m.value}}},
      {"heading_mae_deg",
       {{"nominal", s.nominal.heading_deg.value},
        {"calibrated", s.calibrated.heading_deg.value},
        {"exact", s.exact.heading_deg.value}}},
      {"position_mae_standard_error_m",
       {{"nominal", s.nominal.position_m.standard_error},
        {"calibrated", s.calibrated.position_m.standard_error},
        {"exact", s.exact.position_m.standard_error}}},
      {"heading_mae_standard_error_deg",
       {{"nominal", s.nominal.heading_deg.standard_error},
        {"calibrated", s.calibrated.heading_deg.standard_error},
        {"exact", s.exact.heading_deg.standard_error}}},
      {"position_change_percent", estimate_json(s.position_change, 100.0)},
      {"heading_change_percent", estimate_json(s.heading_change, 100.0)},
      {"exact_position_change_percent", estimate_json(s.exact_position_change, 100.0)},
      {"exact_heading_change_percent", estimate_json(s.exact_heading_change, 100.0)},
      {"position_change_spread_percent", spread_json(s.position_spread, s.position_worse)},
      {"heading_change_spread_percent", spread_json(s.heading_spread, s.heading_worse)}};
  j["paper"] = {
      {"position_mae_m", {{"nominal", kPaperPosNominalM}, {"calibrated", kPaperPosCalibratedM}}},
      {"heading_mae_deg",
       {{"nominal", kPaperHeadNominalDeg}, {"calibrated", kPaperHeadCalibratedDeg}}},
      {"position_change_percent", 100.0 * kPaperPosChange},
      {"heading_change_percent", 100.0 * kPaperHeadChange}};
  j["nominal_runs"] = runs_json(study.nominal);
  j["exact_runs"] = runs_json(study.exact);
  j["calibrations"] = nlohmann::json::array();
  for (std::size_t k = 0; k < study.calibrated.size(); ++k) {
    const CalibratedModel& c = study.calibrated[k];
    nlohmann::json modules = nlohmann::json::array();
    for (const SwpcModuleParams& m : c.tracked.model.modules) {
      modules.push_back({{"x_m", m.x_m},
                         {"y_m", m.y_m},
                         {"steering_offset_rad", m.steering_offset_rad},
                         {"caster_offset_m", m.caster_offset_m},
                         {"wheel_radius_m", m.wheel_radius_m}});
    }
    j["calibrations"].push_back({{"calibration_seed", c.calibration_seed},
                                 {"procedure_duration_s", c.calibration_duration_s},
                                 {"position_change_percent", 100.0 * s.seed_position_change[k]},
                                 {"heading_change_percent", 100.0 * s.seed_heading_change[k]},
                                 {"modules", modules},
                                 {"runs", runs_json(c.tracked)}});
  }
  std::ofstream(dir / "results.json") << j.dump(2) << '\n';
  plot_square_runs(dir, study, kSideM);
  plot_square_spread(dir, s, {kPaperPosChange, kPaperHeadChange});
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::printf("\nwrote %s, %s and %s (%.1f s)\n", (dir / "results.json").c_str(),
              (dir / "square.png").c_str(), (dir / "square_spread.png").c_str(), wall_s);
  return 0;
}

}  // namespace

void add_reproduce_square_command(CLI::App& reproduce, int& exit_code) {
  auto options = std::make_shared<SquareOptions>();
  CLI::App* cmd = reproduce.add_subcommand(
      "square",
      "Square tracking on odometry with design vs calibrated parameters, over many simulated "
      "calibrations and runs (the paper's Table 5 and Fig. 13)");
  cmd->add_option("--calibrations", options->calibrations,
                  "simulated calibrations (seeds), each tracked --runs times per direction")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--runs", options->runs, "square runs per direction and model")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "base seed of every draw")->capture_default_str();
  cmd->add_option("--out", options->out_dir,
                  "directory for results.json, square.png and square_spread.png")
      ->capture_default_str();
  cmd->add_option("--slip-std", options->slip_std, "wheel slip, relative 1-sigma")
      ->check(CLI::Range(0.0, 0.2))
      ->capture_default_str();
  cmd->add_option("--scrub-std", options->scrub_std, "lateral scrub, fraction of speed 1-sigma")
      ->check(CLI::Range(0.0, 0.2))
      ->capture_default_str();
  cmd->add_option("--substep-s", options->substep_s,
                  "the simulator's integration step on the square, s")
      ->check(CLI::Range(1e-4, 0.01))
      ->capture_default_str();
  cmd->add_option("--rotation-deg", options->rotation_deg,
                  "rotation recorded per calibration run (the daemon's default: 300)")
      ->check(CLI::Range(30.0, 720.0))
      ->capture_default_str();
  cmd->add_option("--jobs", options->jobs,
                  "threads (default: one per core; the figures do not depend on it)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  cmd->add_flag("--short", options->short_mode,
                "2 calibrations, 2 runs per direction, 1 lap (for the test suite)");
  cmd->add_option("--calibrated-model", options->calibrated_model,
                  "track with this calibrated model (e.g. written by swiveld) instead of "
                  "calibrating the simulated robot here")
      ->check(CLI::ExistingFile);
  cmd->callback([options, &exit_code]() { exit_code = run_square_reproduction(*options); });
}

}  // namespace swivel::lab
