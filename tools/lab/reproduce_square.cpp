// swivel-lab reproduce square: the tracking test of PAPERS.md §1 (Table 5, Fig. 13). The
// simulated robot's true parameters are the paper's calibrated values (Table 4); it follows
// a 2.5 m square on its own odometry, once with the design values and once with the values
// our calibration recovers from a simulated calibration of that robot, or the values of a
// calibrated model file given with --calibrated-model (e.g. the one swiveld wrote).

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "square_experiment.hpp"
#include "swivel/calibration/calibration_io.hpp"
#include "swivel/calibration/monte_carlo.hpp"
#include "swivel/calibration/simulated_procedure.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::lab {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = std::numbers::pi / 180.0;

// Table 5 of the paper, for the side-by-side print only.
constexpr double kPaperPosNominalM = 0.4674;
constexpr double kPaperPosCalibratedM = 0.1655;
constexpr double kPaperHeadNominalDeg = 9.6721;
constexpr double kPaperHeadCalibratedDeg = 1.9200;

struct SquareOptions {
  int runs = 4;
  std::uint64_t seed = 1;
  std::string out_dir = "square";
  bool short_mode = false;
  double slip_std = 0.01;
  double scrub_std = 0.005;
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

struct Case {
  bool ccw = true;
  int run = 0;
  SquareRunResult nominal;
  SquareRunResult calibrated;
};

std::string quote(const fs::path& p) {
  std::string s = "'";
  for (char c : p.string()) s += c == '\'' ? std::string("''") : std::string(1, c);
  return s + "'";
}

void write_trace(const fs::path& file, const std::vector<Pose2>& trace) {
  std::ofstream f(file);
  f << "# x_m y_m (true)\n0 0\n";
  for (const Pose2& p : trace) f << p.x_m << ' ' << p.y_m << '\n';
}

void plot(const fs::path& dir, const std::vector<Case>& cases, double side_m) {
  {
    std::ofstream f(dir / "commanded.dat");
    const double s = side_m;
    f << "0 0\n" << s << " 0\n" << s << ' ' << s << "\n0 " << s << "\n0 0\n\n\n";
    f << "0 0\n" << s << " 0\n" << s << ' ' << -s << "\n0 " << -s << "\n0 0\n";
  }
  const fs::path script = dir / "square.gp";
  std::ofstream gp(script);
  gp << "set terminal pngcairo size 1000,1000 font ',11'\n"
     << "set output " << quote(dir / "square.png") << "\n"
     << "set title 'Square tracking on odometry (true trajectories), CCW above, CW below'\n"
     << "set xlabel 'x [m]'\nset ylabel 'y [m]'\nset size ratio -1\nset grid\n"
     << "set key outside bottom center horizontal\n"
     << "plot " << quote(dir / "commanded.dat")
     << " index 0:1 with lines lw 2 lc rgb 'black' dt 2 title 'commanded'";
  bool first_nominal = true;
  bool first_calibrated = true;
  for (const Case& c : cases) {
    const std::string tag = std::string(c.ccw ? "ccw" : "cw") + "_" + std::to_string(c.run + 1);
    write_trace(dir / ("nominal_" + tag + ".dat"), c.nominal.trace);
    write_trace(dir / ("calibrated_" + tag + ".dat"), c.calibrated.trace);
    gp << ", " << quote(dir / ("nominal_" + tag + ".dat")) << " with lines lc rgb '#d62728' "
       << (first_nominal ? "title 'nominal parameters'" : "notitle");
    gp << ", " << quote(dir / ("calibrated_" + tag + ".dat")) << " with lines lc rgb '#1f77b4' "
       << (first_calibrated ? "title 'calibrated parameters'" : "notitle");
    first_nominal = first_calibrated = false;
  }
  gp << "\n";
  gp.close();
  const std::string cmd = "gnuplot " + quote(script) + " 2>&1";
  if (std::system(cmd.c_str()) != 0) {
    throw std::runtime_error("gnuplot failed on " + script.string());
  }
}

int run_square_reproduction(const SquareOptions& o) {
  const int runs = o.short_mode ? 1 : o.runs;
  const int laps = o.short_mode ? 1 : 2;
  const RobotModel nominal = design_model();
  const RobotModel truth = table4_model();

  // Our calibration of the true robot, from a simulated calibration with default noise, or
  // a calibrated model from a file.
  RobotModel calibrated;
  if (o.calibrated_model.empty()) {
    calibration::SimulatedProcedureOptions cal_options;
    cal_options.sim.seed = o.seed;
    const calibration::SimulatedCalibration sc =
        calibration::run_simulated_calibration(nominal, truth, cal_options);
    if (!sc.result.ok()) {
      std::fprintf(stderr, "reproduce square: the simulated calibration was refused: %s\n",
                   sc.result.reason().c_str());
      return 2;
    }
    calibrated = calibration::calibrated_model(nominal, sc.result);
  } else {
    calibrated = load_robot_model(o.calibrated_model);
    if (calibrated.drivetrain != DrivetrainKind::kSwpc ||
        calibrated.modules.size() != truth.modules.size()) {
      std::fprintf(stderr, "reproduce square: %s: expected an swpc model with %zu modules\n",
                   o.calibrated_model.c_str(), truth.modules.size());
      return 2;
    }
  }
  std::printf("Table 5 reproduction: square tracking on odometry, nominal vs calibrated\n");
  std::printf("true robot: the paper's calibrated values (Table 4); nominal: design values\n");
  if (o.calibrated_model.empty()) {
    std::printf("calibrated: recovered by a simulated calibration (the daemon's procedure, "
                "default noise)\n");
  } else {
    std::printf("calibrated: %s\n", o.calibrated_model.c_str());
  }
  std::printf("  %-6s %-12s %-12s %-12s %-12s  (recovered - true)\n", "module", "pos [mm]",
              "delta [deg]", "d [mm]", "r [mm]");
  for (std::size_t i = 0; i < truth.modules.size(); ++i) {
    const SwpcModuleParams& e = calibrated.modules[i];
    const SwpcModuleParams& t = truth.modules[i];
    std::printf("  %-6zu %-12.4f %-12.4f %-12.4f %-12.4f\n", i + 1,
                std::hypot(e.x_m - t.x_m, e.y_m - t.y_m) * 1e3,
                calibration::wrap_pi(e.steering_offset_rad - t.steering_offset_rad) / kDeg,
                (e.caster_offset_m - t.caster_offset_m) * 1e3,
                (e.wheel_radius_m - t.wheel_radius_m) * 1e3);
  }
  std::printf(
      "path: %.1f m square, %d lap(s), CCW and CW, %d run(s) each, 0.2 m/s, 90 deg turns in "
      "place; non-systematic: wheel slip %.1f %%, lateral scrub %.1f %% (1-sigma, 0.5 s "
      "correlation), gyro/encoder/motion-capture noise of the model; seed %llu\n",
      2.5, laps, runs, o.slip_std * 100.0, o.scrub_std * 100.0,
      static_cast<unsigned long long>(o.seed));

  std::vector<Case> cases;
  for (const bool ccw : {false, true}) {
    for (int k = 0; k < runs; ++k) {
      SquareRunOptions ro;
      ro.laps = laps;
      ro.counter_clockwise = ccw;
      ro.seed = o.seed * 1000 + static_cast<std::uint64_t>(k) * 10 + (ccw ? 1 : 0);
      ro.nonsystematic.wheel_slip_std = o.slip_std;
      ro.nonsystematic.lateral_scrub_std = o.scrub_std;
      Case c;
      c.ccw = ccw;
      c.run = k;
      c.nominal = run_square(truth, nominal, ro);
      c.calibrated = run_square(truth, calibrated, ro);
      if (!c.nominal.finished || !c.calibrated.finished) {
        throw std::runtime_error("square run did not finish within its time limit");
      }
      std::printf("  %-3s run %d: end error nominal %.4f m %.3f deg, calibrated %.4f m %.3f deg\n",
                  ccw ? "CCW" : "CW", k + 1, c.nominal.position_error_m,
                  c.nominal.heading_error_rad / kDeg, c.calibrated.position_error_m,
                  c.calibrated.heading_error_rad / kDeg);
      cases.push_back(std::move(c));
    }
  }
  double pos_nom = 0.0, pos_cal = 0.0, head_nom = 0.0, head_cal = 0.0;
  for (const Case& c : cases) {
    pos_nom += c.nominal.position_error_m;
    pos_cal += c.calibrated.position_error_m;
    head_nom += c.nominal.heading_error_rad;
    head_cal += c.calibrated.heading_error_rad;
  }
  const auto count = static_cast<double>(cases.size());
  pos_nom /= count;
  pos_cal /= count;
  head_nom /= count * kDeg;
  head_cal /= count * kDeg;
  const double pos_red = (pos_cal - pos_nom) / pos_nom * 100.0;
  const double head_red = (head_cal - head_nom) / head_nom * 100.0;

  std::printf("\nend-pose mean absolute error over %zu runs\n", cases.size());
  std::printf("  %-14s %-12s %-12s %-10s | %-12s %-12s %-10s\n", "", "measured:", "", "",
              "paper:", "", "");
  std::printf("  %-14s %-12s %-12s %-10s | %-12s %-12s %-10s\n", "", "nominal", "calibrated",
              "change", "nominal", "calibrated", "change");
  std::printf("  %-14s %-12.4f %-12.4f %+8.2f %%  | %-12.4f %-12.4f %+8.2f %%\n", "position [m]",
              pos_nom, pos_cal, pos_red, kPaperPosNominalM, kPaperPosCalibratedM, -64.60);
  std::printf("  %-14s %-12.4f %-12.4f %+8.2f %%  | %-12.4f %-12.4f %+8.2f %%\n", "heading [deg]",
              head_nom, head_cal, head_red, kPaperHeadNominalDeg, kPaperHeadCalibratedDeg, -80.15);

  fs::create_directories(o.out_dir);
  const fs::path dir(o.out_dir);
  nlohmann::json j;
  j["experiment"] = "PAPERS.md §1 Table 5: square tracking on odometry";
  j["settings"] = {{"side_m", 2.5},       {"laps", laps},         {"runs_per_direction", runs},
                   {"speed_mps", 0.2},    {"seed", o.seed},       {"wheel_slip_std", o.slip_std},
                   {"lateral_scrub_std", o.scrub_std}, {"short", o.short_mode}};
  if (!o.calibrated_model.empty()) j["calibrated_model"] = o.calibrated_model;
  j["measured"] = {{"position_mae_m", {{"nominal", pos_nom}, {"calibrated", pos_cal}}},
                   {"heading_mae_deg", {{"nominal", head_nom}, {"calibrated", head_cal}}},
                   {"position_change_percent", pos_red},
                   {"heading_change_percent", head_red}};
  j["paper"] = {{"position_mae_m", {{"nominal", kPaperPosNominalM}, {"calibrated", kPaperPosCalibratedM}}},
                {"heading_mae_deg", {{"nominal", kPaperHeadNominalDeg}, {"calibrated", kPaperHeadCalibratedDeg}}},
                {"position_change_percent", -64.60},
                {"heading_change_percent", -80.15}};
  j["runs"] = nlohmann::json::array();
  for (const Case& c : cases) {
    j["runs"].push_back({{"direction", c.ccw ? "ccw" : "cw"},
                         {"run", c.run + 1},
                         {"nominal", {{"position_error_m", c.nominal.position_error_m},
                                      {"heading_error_deg", c.nominal.heading_error_rad / kDeg}}},
                         {"calibrated", {{"position_error_m", c.calibrated.position_error_m},
                                         {"heading_error_deg", c.calibrated.heading_error_rad / kDeg}}}});
  }
  std::ofstream(dir / "results.json") << j.dump(2) << '\n';
  plot(dir, cases, 2.5);
  std::printf("\nwrote %s and %s\n", (dir / "results.json").c_str(), (dir / "square.png").c_str());
  return 0;
}

}  // namespace

void add_reproduce_square_command(CLI::App& reproduce, int& exit_code) {
  auto options = std::make_shared<SquareOptions>();
  CLI::App* cmd = reproduce.add_subcommand(
      "square",
      "Square tracking on odometry with nominal vs calibrated parameters (the paper's Table 5 "
      "and Fig. 13)");
  cmd->add_option("--runs", options->runs, "runs per direction")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "random seed")->capture_default_str();
  cmd->add_option("--out", options->out_dir, "directory for square.png and results.json")
      ->capture_default_str();
  cmd->add_option("--slip-std", options->slip_std, "wheel slip, relative 1-sigma")
      ->check(CLI::Range(0.0, 0.2))
      ->capture_default_str();
  cmd->add_option("--scrub-std", options->scrub_std, "lateral scrub, fraction of speed 1-sigma")
      ->check(CLI::Range(0.0, 0.2))
      ->capture_default_str();
  cmd->add_flag("--short", options->short_mode, "1 run per direction, 1 lap (for the test suite)");
  cmd->add_option("--calibrated-model", options->calibrated_model,
                  "track with this calibrated model (e.g. written by swiveld) instead of "
                  "calibrating the simulated robot here")
      ->check(CLI::ExistingFile);
  cmd->callback([options, &exit_code]() { exit_code = run_square_reproduction(*options); });
}

}  // namespace swivel::lab
