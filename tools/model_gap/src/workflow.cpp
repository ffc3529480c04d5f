// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/workflow.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

#include "swivel/model_gap/command_replay.hpp"
#include "swivel/model_gap/sensor_replay.hpp"
#include "swivel/pose_math.hpp"
#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Rows averaged into each end of a window (sensor_replay.cpp's anchors): 2 h + 1.
constexpr double kAnchorRows = 11.0;

double percentile(std::vector<double> v, double q) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// Derivative by central differences over +-h rows.
std::vector<double> derivative(const std::vector<double>& t, const std::vector<double>& v,
                               std::size_t h) {
  const std::size_t n = t.size();
  std::vector<double> d(n, kNaN);
  for (std::size_t k = h; k + h < n; ++k) d[k] = (v[k + h] - v[k - h]) / (t[k + h] - t[k - h]);
  return d;
}

// How hard the robot accelerated and steered in the run (the limits' starting values).
MotionPeaks motion_peaks(const RunData& run, const std::vector<Pose2>& path) {
  const std::size_t n = run.size();
  std::vector<double> vx(n), vy(n), yaw(n);
  for (std::size_t k = 0; k < n; ++k) {
    vx[k] = path[k].x_m;
    vy[k] = path[k].y_m;
    yaw[k] = path[k].yaw_rad;
  }
  vx = derivative(run.t_s, vx, 5);
  vy = derivative(run.t_s, vy, 5);
  const std::vector<double> w = derivative(run.t_s, yaw, 5);
  const std::vector<double> ax = derivative(run.t_s, vx, 5);
  const std::vector<double> ay = derivative(run.t_s, vy, 5);
  const std::vector<double> aw = derivative(run.t_s, w, 5);
  std::vector<double> a(n);
  for (std::size_t k = 0; k < n; ++k) a[k] = std::hypot(ax[k], ay[k]);
  std::vector<double> abs_aw(n);
  for (std::size_t k = 0; k < n; ++k) abs_aw[k] = std::abs(aw[k]);
  MotionPeaks peaks;
  peaks.accel_mps2 = percentile(a, 0.99);
  peaks.angular_accel_radps2 = percentile(abs_aw, 0.99);
  std::vector<double> steer_rates;
  for (std::size_t i = 0; i < run.steer_rad.size(); ++i) {
    const std::vector<double> r = derivative(run.t_s, run.steer_rad[i], 2);
    for (double x : r) steer_rates.push_back(std::abs(x));
  }
  peaks.steer_rate_radps = percentile(steer_rates, 0.995);
  return peaks;
}

PoseGap pose_gap(Question q, const RunData& run, const std::vector<Pose2>& before,
                 const std::vector<Pose2>& after) {
  PoseGap g;
  g.question = q;
  double sb = 0.0, sa = 0.0, hb = 0.0, ha = 0.0, count = 0.0;
  for (std::size_t k = 0; k < run.size(); ++k) {
    if (!std::isfinite(run.truth_x_m[k]) || !std::isfinite(before[k].x_m) ||
        !std::isfinite(after[k].x_m))
      continue;
    const double pb =
        std::hypot(run.truth_x_m[k] - before[k].x_m, run.truth_y_m[k] - before[k].y_m);
    const double pa = std::hypot(run.truth_x_m[k] - after[k].x_m, run.truth_y_m[k] - after[k].y_m);
    const double yb = wrap_pi(run.truth_yaw_rad[k] - before[k].yaw_rad);
    const double ya = wrap_pi(run.truth_yaw_rad[k] - after[k].yaw_rad);
    sb += pb * pb;
    sa += pa * pa;
    hb += yb * yb;
    ha += ya * ya;
    count += 1.0;
    g.final_position_m_before = pb;
    g.final_position_m_after = pa;
    g.final_heading_rad_before = std::abs(yb);
    g.final_heading_rad_after = std::abs(ya);
  }
  if (count > 0.0) {
    g.rms_position_m_before = std::sqrt(sb / count);
    g.rms_position_m_after = std::sqrt(sa / count);
    g.rms_heading_rad_before = std::sqrt(hb / count);
    g.rms_heading_rad_after = std::sqrt(ha / count);
  }
  return g;
}

// Noise floors: what the sensors the model states can resolve in one window.
double position_floor(const RobotModel& m) {
  const double p = m.sensors.motion_capture.position_noise_m;
  return std::max(2.0 * p * p / kAnchorRows, 1e-14);
}
double heading_floor(const RobotModel& m) {
  const double y = m.sensors.motion_capture.yaw_noise_rad;
  return std::max(2.0 * y * y / kAnchorRows, 1e-14);
}
double count_floor(double counts_per_rev) {
  const double q = 2.0 * std::numbers::pi / std::max(counts_per_rev, 1.0);
  return q * q / 6.0;
}

}  // namespace

std::vector<FittedEffect> GapResult::named() const {
  std::vector<FittedEffect> out = sensor.named;
  out.insert(out.end(), command.named.begin(), command.named.end());
  return out;
}

GapResult analyse_gap(const RobotModel& nominal, const RunData& run, const GapOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  GapResult result;
  result.options = options;
  result.nominal = nominal;
  result.run_source = run.source;
  result.t_s = run.t_s;
  for (std::size_t k = 0; k < run.size(); ++k) {
    result.motion_capture.push_back(
        Pose2{run.truth_x_m[k], run.truth_y_m[k], run.truth_yaw_rad[k]});
  }
  result.segments = phase_segments(classify_phases(run.commands()), run.t_s);

  const SensorReplay sensors(nominal, run, options.window_s);
  const std::vector<Window>& windows = sensors.windows();
  const std::size_t w = windows.size();
  if (w < 10) {
    throw std::invalid_argument(
        "run " + run.source + " gives " + std::to_string(w) + " windows of " +
        std::to_string(options.window_s) +
        " s with motion capture at both ends; the workflow needs at least 10");
  }
  const WindowMotion& motion = sensors.motion();
  for (std::size_t j = 0; j < w; ++j) result.window_start_s.push_back(motion.start_s[j]);
  std::vector<double> travel_sq(w);
  std::vector<double> steer_sq(w);
  std::vector<double> accel(w);
  for (std::size_t j = 0; j < w; ++j) {
    travel_sq[j] = motion.wheel_travel_rad[j] * motion.wheel_travel_rad[j];
    steer_sq[j] = motion.steer_travel_rad[j] * motion.steer_travel_rad[j];
    // A turn's angular acceleration counts as the acceleration of a point 0.2 m out.
    accel[j] = motion.accel_mps2[j] + 0.2 * motion.angular_accel_radps2[j];
  }
  std::vector<double> start_yaw(w);
  std::vector<Pose2> measured_change(w);
  for (std::size_t j = 0; j < w; ++j) {
    start_yaw[j] = sensors.anchors_start()[j].yaw_rad;
    measured_change[j] = between(sensors.anchors_start()[j], sensors.anchors_end()[j]);
  }

  // Question 1: sensor to pose.
  QuestionReplay sq;
  sq.channels = sensors.channels();
  sq.windows = w;
  sq.residuals = [&sensors](const RobotModel& model, std::span<const double>,
                            std::vector<double>& out, std::size_t window_limit) {
    return sensors.residuals(sim::resolve_plant(model), out, window_limit);
  };
  for (std::size_t c = 0; c < sq.channels.size(); ++c) {
    sq.noise_x.push_back(travel_sq);
    sq.noise_floor.push_back(sq.channels[c].kind == ChannelKind::kPosition
                                 ? position_floor(nominal)
                                 : heading_floor(nominal));
  }
  sq.own_change.resize(sq.channels.size() * w);
  for (std::size_t j = 0; j < w; ++j) {
    sq.own_change[0 * w + j] = measured_change[j].x_m;
    sq.own_change[1 * w + j] = measured_change[j].y_m;
    sq.own_change[2 * w + j] = measured_change[j].yaw_rad;
    sq.own_change[3 * w + j] = measured_change[j].yaw_rad;
  }
  sq.accel = accel;
  sq.start_yaw_rad = start_yaw;
  sq.wheel_sin_change = motion.wheel_sin_change;
  sq.wheel_cos_change = motion.wheel_cos_change;
  sensors.path(sim::resolve_plant(nominal), result.dead_reckoning_before);
  const MotionPeaks peaks = motion_peaks(run, result.dead_reckoning_before);
  result.sensor = analyse_question(Question::kSensorToPose, nominal, sq,
                                   candidate_library(nominal, Question::kSensorToPose, peaks),
                                   options.question);
  // The command question starts from what the sensors showed, unless they showed something
  // the library cannot name.
  const RobotModel command_base =
      result.sensor.verdict == Verdict::kNamed ? result.sensor.augmented : nominal;
  sensors.path(sim::resolve_plant(command_base), result.dead_reckoning_after);

  // Question 2: command to motion.
  result.command_assessed = !options.sensor_only;
  result.augmented = command_base;
  if (result.command_assessed) {
    const CommandReplay commands(nominal, run, sensors, result.dead_reckoning_before);
    QuestionReplay cq;
    cq.channels = commands.channels();
    cq.windows = w;
    cq.residuals = [&commands](const RobotModel& model, std::span<const double> nuisance,
                               std::vector<double>& out, std::size_t window_limit) {
      return commands.residuals(model, nuisance.empty() ? 0.0 : nuisance[0], out, window_limit);
    };
    const double row = commands.row_period_s();
    cq.nuisance.push_back({"command_delay_s", 0.0, row, -CommandReplay::kMaxCommandDelayRows * row,
                           CommandReplay::kMaxCommandDelayRows * row});
    cq.own_change.resize(cq.channels.size() * w);
    for (std::size_t c = 0; c < cq.channels.size(); ++c) {
      const ChannelInfo& info = cq.channels[c];
      const bool steer = info.kind == ChannelKind::kSteerAngle;
      const std::vector<double>& angle =
          steer ? run.steer_rad[info.module] : run.wheel_rad[info.module];
      cq.noise_x.push_back(steer ? steer_sq : travel_sq);
      cq.noise_floor.push_back(count_floor(steer ? nominal.sensors.steering_encoder_counts_per_rev
                                                 : nominal.sensors.wheel_encoder_counts_per_rev));
      for (std::size_t j = 0; j < w; ++j)
        cq.own_change[c * w + j] = angle[windows[j].b] - angle[windows[j].a];
    }
    cq.known_variance_of = [&commands](const RobotModel& model, std::span<const double> nuisance) {
      return commands.timing_variance(model, nuisance.empty() ? 0.0 : nuisance[0]);
    };
    cq.accel = accel;
    cq.start_yaw_rad = start_yaw;
    cq.wheel_sin_change = motion.wheel_sin_change;
    cq.wheel_cos_change = motion.wheel_cos_change;
    result.command = analyse_question(
        Question::kCommandToMotion, command_base, cq,
        candidate_library(command_base, Question::kCommandToMotion, peaks, row), options.question);
    result.command_delay_s = result.command.nuisance.empty() ? 0.0 : result.command.nuisance[0];
    if (result.command.verdict == Verdict::kNamed) result.augmented = result.command.augmented;
    commands.path(nominal, result.command_delay_s, result.replay_before);
    commands.path(result.augmented, result.command_delay_s, result.replay_after);
  } else {
    result.command.question = Question::kCommandToMotion;
    result.command.summary = "Command to motion: not assessed.";
  }

  result.pose_gaps.push_back(pose_gap(Question::kSensorToPose, run, result.dead_reckoning_before,
                                      result.dead_reckoning_after));
  if (result.command_assessed) {
    result.pose_gaps.push_back(
        pose_gap(Question::kCommandToMotion, run, result.replay_before, result.replay_after));
  }
  result.summary = result.sensor.summary + "\n" + result.command.summary;
  result.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace swivel::model_gap
