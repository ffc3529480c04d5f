// SPDX-License-Identifier: Apache-2.0
#include "swivel/calibration/calibration_io.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace swivel::calibration {
namespace {

constexpr char kCommentPrefix[] = "calibration:";

std::string format_number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

// `where` and `key` name the field in an error, built only then.
double parse_number(const std::string& text, const std::string& where, const std::string& key) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v)) {
    throw std::invalid_argument(where + " " + key + ": '" + text + "' is not a finite number");
  }
  return v;
}

}  // namespace

std::string calibration_comment(const LockSpec& lock, double yaw_rate_radps) {
  std::string line =
      std::string(kCommentPrefix) + " locked_module " + std::to_string(lock.locked_module + 1);
  if (lock.declared_steer_rad)
    line += ", locked_steer_rad " + format_number(*lock.declared_steer_rad);
  line += ", yaw_rate_radps " + format_number(yaw_rate_radps);
  return line;
}

std::optional<LockSpec> lock_from_comments(const RunLog& log) {
  for (const std::string& comment : log.header.comments) {
    if (comment.rfind(kCommentPrefix, 0) != 0) continue;
    const std::string where = log.source + ": '# " + comment + "'";
    LockSpec lock;
    bool have_module = false;
    std::stringstream fields(comment.substr(sizeof kCommentPrefix - 1));
    std::string field;
    while (std::getline(fields, field, ',')) {
      field = trim(field);
      const auto space = field.find(' ');
      if (space == std::string::npos) {
        // Once, on the way out. NOLINTNEXTLINE(performance-inefficient-string-concatenation)
        throw std::invalid_argument(where + ": expected 'key value' pairs, got '" + field + "'");
      }
      const std::string key = field.substr(0, space);
      const double value = parse_number(trim(field.substr(space + 1)), where, key);
      if (key == "locked_module") {
        if (value < 1.0 || value != std::floor(value)) {
          throw std::invalid_argument(where + ": locked_module must be a module number >= 1");
        }
        lock.locked_module = static_cast<std::size_t>(value) - 1;
        have_module = true;
      } else if (key == "locked_steer_rad") {
        lock.declared_steer_rad = value;
      }
      // Other keys (yaw rate, ...) describe the run but do not enter the calibration.
    }
    if (!have_module) throw std::invalid_argument(where + ": no locked_module");
    return lock;
  }
  return std::nullopt;
}

LockedRun locked_run_from_log(const RunLog& log, const LockSpec& lock) {
  const std::size_t n = log.header.module_count;
  if (log.header.drivetrain != DrivetrainKind::kSwpc) {
    throw std::invalid_argument(log.source + ": not an swpc log (calibration needs casters)");
  }
  if (lock.locked_module >= n) {
    throw std::invalid_argument(log.source + ": locked module " +
                                std::to_string(lock.locked_module + 1) + " but the robot has " +
                                std::to_string(n) + " modules");
  }
  LockedRun run;
  run.locked_module = lock.locked_module;
  RunSeries& d = run.data;
  d.wheel_angle_rad.assign(n, {});
  d.steer_angle_rad.assign(n, {});
  // Steering encoders may wrap to (-pi, pi]: unwrapped over every row, not only those kept.
  std::array<double, kMaxModules> steer{};
  for (std::size_t k = 0; k < log.samples.size(); ++k) {
    const RunLogSample& s = log.samples[k];
    for (std::size_t m = 0; m < n; ++m) {
      steer[m] = k == 0 ? s.steer_rad[m] : unwrap_near(s.steer_rad[m], steer[m]);
    }
    if (!s.has_truth) continue;
    d.t_s.push_back(s.t_s);
    d.x_m.push_back(s.truth.x_m);
    d.y_m.push_back(s.truth.y_m);
    d.yaw_rad.push_back(s.truth.yaw_rad);
    for (std::size_t m = 0; m < n; ++m) {
      d.wheel_angle_rad[m].push_back(s.wheel_rad[m]);
      d.steer_angle_rad[m].push_back(steer[m]);
    }
  }
  if (d.t_s.size() < 2) {
    throw std::invalid_argument(log.source + ": " + std::to_string(d.t_s.size()) +
                                " rows with motion capture; the calibration needs the robot's "
                                "trajectory");
  }
  const std::vector<double>& locked_steer = d.steer_angle_rad[lock.locked_module];
  double sum = 0.0;
  for (double v : locked_steer) sum += v;
  run.locked_steer_meas_rad = sum / static_cast<double>(locked_steer.size());
  if (lock.declared_steer_rad &&
      std::abs(wrap_pi(*lock.declared_steer_rad - run.locked_steer_meas_rad)) >
          kMaxDeclaredLockMismatchRad) {
    constexpr double kDeg = 180.0 / std::numbers::pi;
    std::ostringstream msg;
    msg.precision(4);
    msg << log.source << ": module " << lock.locked_module + 1 << " declared locked at "
        << *lock.declared_steer_rad * kDeg << " deg but its steering encoder reads "
        << run.locked_steer_meas_rad * kDeg << " deg (wrong module or angle?)";
    throw std::invalid_argument(msg.str());
  }
  return run;
}

CalibrationInput calibration_input_from_logs(const std::vector<RunLog>& logs,
                                             const std::vector<LockSpec>& locks) {
  if (logs.size() != locks.size()) {
    throw std::invalid_argument("calibration: " + std::to_string(logs.size()) + " logs but " +
                                std::to_string(locks.size()) + " lock descriptions");
  }
  CalibrationInput input;
  for (std::size_t j = 0; j < logs.size(); ++j) {
    const RunLog& log = logs[j];
    if (j > 0 && (log.header.module_count != logs[0].header.module_count ||
                  log.header.robot != logs[0].header.robot)) {
      throw std::invalid_argument(log.source + ": robot '" + log.header.robot + "' with " +
                                  std::to_string(log.header.module_count) +
                                  " modules differs from " + logs[0].source + " ('" +
                                  logs[0].header.robot + "', " +
                                  std::to_string(logs[0].header.module_count) + " modules)");
    }
    input.module_count = log.header.module_count;
    input.runs.push_back(locked_run_from_log(log, locks[j]));
  }
  return input;
}

CalibrationOptions calibration_options_for(const RobotModel& model) {
  CalibrationOptions options;
  const double counts = model.sensors.steering_encoder_counts_per_rev;
  if (counts > 0.0) {
    options.steer_encoder_sigma_rad = 2.0 * std::numbers::pi / counts / std::sqrt(12.0);
  }
  return options;
}

RobotModel calibrated_model(const RobotModel& nominal, const CalibrationResult& result) {
  RobotModel out = nominal;
  for (std::size_t m = 0; m < out.modules.size() && m < result.modules.size(); ++m) {
    out.modules[m] = result.modules[m].params;
  }
  out.source_file.clear();
  return out;
}

}  // namespace swivel::calibration
