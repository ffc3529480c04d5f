// SPDX-License-Identifier: Apache-2.0
// swivel-lab calibrate: the geometric calibration of docs/methods.md §1 from recorded run logs
// (two per module), written as a calibrated copy of the nominal robot model.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/calibration/calibration_io.hpp"
#include "swivel/pose_math.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_log.hpp"

namespace swivel::lab {
namespace {

namespace fs = std::filesystem;

struct CalibrateOptions {
  std::string model_file;
  std::vector<std::string> runs;
  std::vector<std::string> locks;
  std::string out_file;
  bool force = false;
};

// "I" or "I:DEG" (1-based module, measured locked angle in degrees).
calibration::LockSpec parse_lock(const std::string& text) {
  const auto colon = text.find(':');
  calibration::LockSpec lock;
  try {
    std::size_t used = 0;
    const std::string module = text.substr(0, colon);
    const long m = std::stol(module, &used);
    if (used != module.size() || m < 1) throw std::invalid_argument("");
    lock.locked_module = static_cast<std::size_t>(m - 1);
    if (colon != std::string::npos) {
      const std::string deg = text.substr(colon + 1);
      const double a = std::stod(deg, &used);
      if (used != deg.size()) throw std::invalid_argument("");
      lock.declared_steer_rad = a * kRadPerDeg;
    }
  } catch (const std::exception&) {
    throw std::invalid_argument("--lock '" + text + "': expected MODULE or MODULE:DEG, e.g. 2:165");
  }
  return lock;
}

std::string default_out(const std::string& model_file) {
  const fs::path p(model_file);
  return (p.parent_path() / (p.stem().string() + "_calibrated.yaml")).string();
}

void print_results(const RobotModel& nominal, const calibration::CalibrationResult& result) {
  std::printf("%-6s %-22s %-22s %-20s %-20s %-20s\n", "module", "x [mm]", "y [mm]", "delta [deg]",
              "d [mm]", "r [mm]");
  for (std::size_t i = 0; i < result.modules.size(); ++i) {
    const auto& p = result.modules[i].params;
    const auto& s = result.modules[i].sigma;
    char x[32];
    char y[32];
    char delta[32];
    char d[32];
    char r[32];
    std::snprintf(x, sizeof x, "%.3f +- %.3f", p.x_m * 1e3, s.x_m * 1e3);
    std::snprintf(y, sizeof y, "%.3f +- %.3f", p.y_m * 1e3, s.y_m * 1e3);
    std::snprintf(delta, sizeof delta, "%.4f +- %.4f", p.steering_offset_rad / kRadPerDeg,
                  s.steering_offset_rad / kRadPerDeg);
    std::snprintf(d, sizeof d, "%.4f +- %.4f", p.caster_offset_m * 1e3, s.caster_offset_m * 1e3);
    std::snprintf(r, sizeof r, "%.4f +- %.4f", p.wheel_radius_m * 1e3, s.wheel_radius_m * 1e3);
    std::printf("%-6zu %-22s %-22s %-20s %-20s %-20s\n", i + 1, x, y, delta, d, r);
  }
  std::printf("(uncertainties 1-sigma; nominal %s)\n", nominal.name.c_str());
}

int run_calibrate(const CalibrateOptions& o) {
  const RobotModel nominal = load_robot_model(o.model_file);
  if (nominal.drivetrain != DrivetrainKind::kSwpc) {
    throw std::invalid_argument(o.model_file + ": calibration needs an swpc robot");
  }
  const std::string out = o.out_file.empty() ? default_out(o.model_file) : o.out_file;
  if (fs::exists(out) && !o.force) {
    throw std::invalid_argument(out + " exists; refusing to overwrite it (use --force)");
  }
  if (!o.locks.empty() && o.locks.size() != o.runs.size()) {
    throw std::invalid_argument("--lock: give one per --run (" + std::to_string(o.runs.size()) +
                                " runs, " + std::to_string(o.locks.size()) + " locks)");
  }

  std::vector<RunLog> logs;
  std::vector<calibration::LockSpec> locks;
  for (std::size_t j = 0; j < o.runs.size(); ++j) {
    logs.push_back(read_run_log(o.runs[j]));
    if (!o.locks.empty()) {
      locks.push_back(parse_lock(o.locks[j]));
    } else if (auto lock = calibration::lock_from_comments(logs.back())) {
      locks.push_back(*lock);
    } else {
      throw std::invalid_argument(o.runs[j] +
                                  ": no '# calibration:' line; say which module it locked "
                                  "with --lock MODULE[:DEG] (one per --run)");
    }
    if (logs.back().header.module_count != nominal.modules.size()) {
      throw std::invalid_argument(
          o.runs[j] + ": " + std::to_string(logs.back().header.module_count) + " modules, but " +
          o.model_file + " has " + std::to_string(nominal.modules.size()));
    }
  }
  const calibration::CalibrationInput input = calibration::calibration_input_from_logs(logs, locks);
  std::printf("calibrating %s from %zu runs:\n", nominal.name.c_str(), input.runs.size());
  for (std::size_t j = 0; j < input.runs.size(); ++j) {
    std::printf("  %s: module %zu locked at %.3f deg, %zu motion-capture samples\n",
                o.runs[j].c_str(), input.runs[j].locked_module + 1,
                input.runs[j].locked_steer_meas_rad / kRadPerDeg, input.runs[j].data.t_s.size());
  }
  const calibration::CalibrationResult result =
      calibration::calibrate(input, calibration::calibration_options_for(nominal));
  std::printf("\nverdict:\n%s", result.verdict.text().c_str());
  if (!result.ok()) {
    std::fflush(stdout);
    std::cerr << "swivel-lab calibrate: refused: " << result.reason() << '\n';
    return 2;
  }
  std::printf("\n");
  print_results(nominal, result);
  save_robot_model(calibration::calibrated_model(nominal, result), out);
  std::printf("wrote %s\n", out.c_str());
  return 0;
}

}  // namespace

void add_calibrate_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<CalibrateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate",
      "Geometric calibration of an SWPC robot from calibration run logs (two locked angles "
      "per module) into a calibrated robot model");
  cmd->add_option("--model", options->model_file, "nominal robot model (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--run", options->runs,
                  "calibration run log (repeatable; 2 per module, each with its '# "
                  "calibration:' line or a --lock)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--lock", options->locks,
                  "locked module (1-based) and optionally its locked angle in deg, MODULE[:DEG], "
                  "one per --run in order; overrides the logs' '# calibration:' lines");
  cmd->add_option("--out", options->out_file,
                  "calibrated model to write (default: <model>_calibrated.yaml next to it)");
  cmd->add_flag("--force", options->force, "overwrite --out if it exists");
  cmd->callback([options, &exit_code]() { exit_code = run_calibrate(*options); });
}

}  // namespace swivel::lab
