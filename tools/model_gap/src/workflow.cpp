// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/workflow.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <span>
#include <sstream>

#include "motion_kind.hpp"
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
  std::vector<double> vx(n);
  std::vector<double> vy(n);
  std::vector<double> yaw(n);
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
  double sb = 0.0;
  double sa = 0.0;
  double hb = 0.0;
  double ha = 0.0;
  double count = 0.0;
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

// What the wheel encoders' quantization adds to a window's heading from the encoders: each
// wheel's rotation is off by count_floor, and the heading weighs a wheel by r / rho over the
// wheels (rho the distance of its contact from the reference point, r its radius).
double encoder_heading_variance(const RobotModel& m) {
  const double q = count_floor(m.sensors.wheel_encoder_counts_per_rev);
  if (m.drivetrain == DrivetrainKind::kDifferential) {
    const DifferentialParams& d = m.differential;
    const double r2 = 0.5 * (d.wheel_radius_left_m * d.wheel_radius_left_m +
                             d.wheel_radius_right_m * d.wheel_radius_right_m);
    return 2.0 * q * r2 / (d.track_width_m * d.track_width_m);
  }
  double r2 = 0.0;
  double rho2 = 0.0;
  for (const SwpcModuleParams& module : m.modules) {
    r2 += module.wheel_radius_m * module.wheel_radius_m;
    rho2 += module.x_m * module.x_m + module.y_m * module.y_m;
  }
  return rho2 > 0.0 ? q * r2 / (rho2 * static_cast<double>(m.modules.size())) : 0.0;
}

// The gyro's stated white noise integrated over a median window, one reading a row.
double gyro_heading_variance(const RobotModel& m, const SensorReplay& sensors) {
  const WindowMotion& motion = sensors.motion();
  std::vector<double> per_window;
  for (std::size_t j = 0; j < sensors.windows().size(); ++j) {
    const Window& w = sensors.windows()[j];
    const double row_s = motion.duration_s[j] / static_cast<double>(w.b - w.a);
    const double sigma = m.sensors.gyro.noise_rad_s;
    per_window.push_back(sigma * sigma * row_s * motion.duration_s[j]);
  }
  if (per_window.empty()) return 0.0;
  auto mid = per_window.begin() + static_cast<std::ptrdiff_t>(per_window.size() / 2);
  std::nth_element(per_window.begin(), mid, per_window.end());
  return *mid;
}

std::string figure(const char* name, double value) {
  std::ostringstream s;
  s << name << " " << value;
  return s.str();
}

// Per channel of the sensor question, the variance per window the model's own figures account
// for, and which figures those are.
void state_sensor_noise(const SensorReplay& sensors, const RobotModel& nominal,
                        QuestionReplay& sq) {
  const MotionCaptureParams& mocap = nominal.sensors.motion_capture;
  for (std::size_t c = 0; c < sq.channels.size(); ++c) {
    if (sq.channels[c].kind == ChannelKind::kPosition) {
      sq.stated_variance.push_back(position_floor(nominal));
      sq.stated_source.push_back(figure("motion_capture.position_noise_m", mocap.position_noise_m));
      continue;
    }
    // Channels dx, dy, then the gyro's heading when the run has one, then the encoders'.
    const bool gyro = sensors.uses_gyro() && c == 2;
    sq.stated_variance.push_back(
        heading_floor(nominal) +
        (gyro ? gyro_heading_variance(nominal, sensors) : encoder_heading_variance(nominal)));
    sq.stated_source.push_back(figure("motion_capture.yaw_noise_rad", mocap.yaw_noise_rad) + ", " +
                               (gyro ? figure("gyro.noise_rad_s", nominal.sensors.gyro.noise_rad_s)
                                     : figure("wheel_encoder_counts_per_rev",
                                              nominal.sensors.wheel_encoder_counts_per_rev)));
  }
}

std::string plus_minus(double value, double sigma, double unit, int precision) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << value * unit << " +- ";
  if (std::isfinite(sigma)) {
    s << sigma * unit;
  } else {
    s << "(not fixed by the run)";
  }
  return s.str();
}

std::vector<double> squared_wheel_travel(const WindowMotion& motion) {
  std::vector<double> out(motion.wheel_travel_rad.size());
  for (std::size_t j = 0; j < out.size(); ++j)
    out[j] = motion.wheel_travel_rad[j] * motion.wheel_travel_rad[j];
  return out;
}

std::vector<double> window_acceleration(const WindowMotion& motion) {
  std::vector<double> out(motion.accel_mps2.size());
  // A turn's angular acceleration counts as the acceleration of a point 0.2 m out.
  for (std::size_t j = 0; j < out.size(); ++j)
    out[j] = motion.accel_mps2[j] + 0.2 * motion.angular_accel_radps2[j];
  return out;
}

}  // namespace

QuestionReplay sensor_question_replay(const SensorReplay& sensors, const RobotModel& nominal) {
  const std::size_t w = sensors.windows().size();
  const WindowMotion& motion = sensors.motion();
  const std::vector<double> travel_sq = squared_wheel_travel(motion);
  QuestionReplay sq;
  sq.channels = sensors.channels();
  sq.windows = w;
  sq.window_start_s = motion.start_s;
  sq.residuals = [&sensors](const RobotModel& model, std::span<const double> nuisance,
                            std::vector<double>& out, std::size_t window_limit) {
    return sensors.residuals(sim::resolve_plant(model), sensors.truth(nuisance), out, window_limit);
  };
  sq.nuisance = sensors.nuisance();
  sq.fit_nuisance_before_noise = true;
  sq.refit_nuisance_with_candidates = true;
  for (std::size_t c = 0; c < sq.channels.size(); ++c) {
    sq.noise_x.push_back(travel_sq);
    sq.noise_floor.push_back(sq.channels[c].kind == ChannelKind::kPosition
                                 ? position_floor(nominal)
                                 : heading_floor(nominal));
  }
  state_sensor_noise(sensors, nominal, sq);
  sq.own_change.resize(sq.channels.size() * w);
  for (std::size_t j = 0; j < w; ++j) {
    const Pose2 change = between(sensors.anchors_start()[j], sensors.anchors_end()[j]);
    sq.own_change[0 * w + j] = change.x_m;
    sq.own_change[1 * w + j] = change.y_m;
    for (std::size_t c = 2; c < sq.channels.size(); ++c) sq.own_change[c * w + j] = change.yaw_rad;
    sq.start_yaw_rad.push_back(sensors.anchors_start()[j].yaw_rad);
  }
  sq.accel = window_acceleration(motion);
  sq.wheel_sin_change = motion.wheel_sin_change;
  sq.wheel_cos_change = motion.wheel_cos_change;
  return sq;
}

PoseGap compare_paths(Question question, const RunData& run, const std::vector<Pose2>& before,
                      const std::vector<Pose2>& after) {
  return pose_gap(question, run, before, after);
}

std::vector<std::string> truth_nuisance_lines(const GapResult& r) {
  std::vector<std::string> out;
  const std::vector<double>& v = r.sensor.nuisance;
  const std::vector<double>& s = r.sensor.nuisance_sigmas;
  const auto sigma = [&s](std::size_t i) {
    return i < s.size() ? s[i] : std::numeric_limits<double>::infinity();
  };
  for (std::size_t i = 0; i < std::min(v.size(), r.truth_names.size()); ++i) {
    const std::string& n = r.truth_names[i];
    if (n == "truth.yaw_offset_rad") {
      out.push_back("tracked body's yaw offset (its heading minus the robot's): " +
                    plus_minus(v[i], sigma(i), 1e3, 2) + " mrad");
    } else if (n == "truth.lever_x_m") {
      out.push_back("tracked body's origin, robot x: " + plus_minus(v[i], sigma(i), 1e3, 1) +
                    " mm");
    } else if (n == "truth.lever_y_m") {
      out.push_back("tracked body's origin, robot y: " + plus_minus(v[i], sigma(i), 1e3, 1) +
                    " mm");
    } else if (n == "truth.time_offset_s") {
      out.push_back(
          "motion capture's clock offset (late against the encoders, at the run's "
          "middle): " +
          plus_minus(v[i], sigma(i), 1e3, 1) + " ms");
    } else if (n == "truth.gyro_shift_s") {
      out.push_back("gyro's readings, where between rows the rate they sample belongs (later): " +
                    plus_minus(v[i], sigma(i), 1e3, 2) + " ms");
    } else if (n == "truth.clock_rate") {
      out.push_back("motion capture's clock rate against the encoders' (the offset's growth): " +
                    plus_minus(v[i], sigma(i), 1e3, 2) + " ms/s");
    }
  }
  return out;
}

std::vector<FittedEffect> GapResult::named() const {
  std::vector<FittedEffect> out = sensor.named;
  out.insert(out.end(), command.named.begin(), command.named.end());
  return out;
}

namespace {

// The run as the report shows it: its motion capture, phases and windows.
void record_run(const RunData& run, const SensorReplay& sensors, GapResult& result) {
  result.run_source = run.source;
  result.t_s = run.t_s;
  for (std::size_t k = 0; k < run.size(); ++k) {
    result.motion_capture.push_back(
        Pose2{run.truth_x_m[k], run.truth_y_m[k], run.truth_yaw_rad[k]});
  }
  if (run.has_commands) result.segments = phase_segments(classify_phases(run.commands()), run.t_s);
  if (!sensors.uses_gyro()) {
    result.notes.emplace_back(
        "The run has no gyro: the dead reckoning takes its heading from the encoders, and the "
        "gyro channel and the gyro_bias and gyro_scale candidates are left out.");
  }
  if (sensors.fits_time_offset()) {
    result.notes.emplace_back(
        std::string("The run does not declare a shared clock for motion capture (`# "
                    "truth_clock: shared`): the motion capture's time offset") +
        (sensors.fits_clock_rate()
             ? " and clock rate are fitted (a rate too: the log does not declare `# "
               "truth_clock: same_rate`; a common wheel-radius scale is then fixed only by the "
               "run's changes of speed)"
             : " is fitted") +
        ", and sensor_latency, which this question cannot tell from it, is not a candidate.");
  }
  const std::size_t w = sensors.windows().size();
  const auto held = static_cast<std::size_t>(std::ranges::count(sensors.scrubbing(), 1));
  if (held > 0) {
    result.notes.emplace_back(
        std::to_string(held) + " of " + std::to_string(w) +
        " windows are not compared in the sensor question: the casters disagreed about the "
        "motion in them (a tyre scrubbed sideways), held back from the angles the motion "
        "needs at a steering rate limit or steering late, which the kinematics cannot "
        "hold.");
  }
  if (w < 10) {
    throw std::invalid_argument(
        "run " + run.source + " gives " + std::to_string(w) + " windows of " +
        std::to_string(result.options.window_s) +
        " s with motion capture at both ends; the workflow needs at least 10");
  }
  for (std::size_t j = 0; j < w; ++j) result.window_start_s.push_back(sensors.motion().start_s[j]);
}

// The sensor question's candidates this run can tell apart; a note for each one left out
// for a reason the run shows.
std::vector<Candidate> sensor_candidates(const RobotModel& nominal, const RunData& run,
                                         const SensorReplay& sensors, const MotionPeaks& peaks,
                                         std::vector<std::string>& notes) {
  std::vector<Candidate> library = candidate_library(nominal, Question::kSensorToPose, peaks);
  if (sensors.fits_body_offset() && nominal.drivetrain == DrivetrainKind::kSwpc) {
    notes.emplace_back(
        "The tracked body's yaw offset is fitted (the log does not declare `# truth_frame: "
        "robot`): on an SWPC robot it trades against the part of the steering offsets common to "
        "every module, which only turning separates; a steering offset is fixed mainly in its "
        "differences between modules.");
  }
  const bool turns_of_one_kind = turn_kind_spread(run) < kMinSpinShareSpread;
  if (turns_of_one_kind && nominal.drivetrain == DrivetrainKind::kDifferential) {
    notes.emplace_back(
        "The run turns in one way only (on the spot, or on arcs of one kind): a turn-dependent "
        "track (track_scrub) cannot be told from a track width, and is not a candidate.");
  }
  const bool radius_hidden_by_lever_arm =
      sensors.fits_body_offset() && drives_one_circle(wheel_steps(run, 1.0));
  if (radius_hidden_by_lever_arm) {
    notes.emplace_back(
        "The run drives one circle and the tracked body's lever arm is fitted: a common "
        "wheel-radius scale changes the circle's radius as the lever arm does, and a left/right "
        "radius difference its heading per metre as a track width does, so wheel_radius is not a "
        "candidate (track_width is). Runs with straight driving or other turns fix the radii.");
  }
  std::erase_if(library, [&](const Candidate& c) {
    const bool gyro = c.name == "gyro_bias" || c.name == "gyro_scale";
    return (gyro && !sensors.uses_gyro()) ||
           (c.name == "sensor_latency" && sensors.fits_time_offset()) ||
           (c.name == "track_scrub" && turns_of_one_kind) ||
           (c.name == "wheel_radius" && radius_hidden_by_lever_arm);
  });
  return library;
}

// Largest steering yield a fit may try, rad: d mu N / Kp for a servo as soft as a fifth of a
// radian of error before its tyre slides.
constexpr double kMaxSteeringYieldRad = 0.2;

// The command replay's nuisance from the fitted values (command delay, then on a caster robot
// the steering yield).
ActuatorNuisance actuator_nuisance(std::span<const double> nuisance) {
  ActuatorNuisance a;
  if (!nuisance.empty()) a.command_delay_s = nuisance[0];
  if (nuisance.size() > 1) a.steering_yield_rad = nuisance[1];
  return a;
}

// The command question: each wheel's and steering angle's change over the windows, replayed
// from the commands (`commands` must outlive the replay).
QuestionReplay command_question_replay(const CommandReplay& commands, const SensorReplay& sensors,
                                       const RobotModel& nominal, const RunData& run) {
  const std::vector<Window>& windows = sensors.windows();
  const std::size_t w = windows.size();
  const WindowMotion& motion = sensors.motion();
  std::vector<double> steer_sq(w);
  for (std::size_t j = 0; j < w; ++j)
    steer_sq[j] = motion.steer_travel_rad[j] * motion.steer_travel_rad[j];
  const std::vector<double> travel_sq = squared_wheel_travel(motion);
  QuestionReplay cq;
  cq.channels = commands.channels();
  cq.windows = w;
  cq.window_start_s = motion.start_s;
  cq.residuals = [&commands](const RobotModel& model, std::span<const double> nuisance,
                             std::vector<double>& out, std::size_t window_limit) {
    return commands.residuals(model, actuator_nuisance(nuisance), out, window_limit);
  };
  const double row = commands.row_period_s();
  cq.nuisance.push_back({"command_delay_s", 0.0, row, -CommandReplay::kMaxCommandDelayRows * row,
                         CommandReplay::kMaxCommandDelayRows * row});
  // From rigid servos (the kinematic replay): the run moves it as far as its servos yield.
  if (run.drivetrain == DrivetrainKind::kSwpc)
    cq.nuisance.push_back({"steering_yield_rad", 0.0, 0.01, 0.0, kMaxSteeringYieldRad});
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
    return commands.timing_variance(model, actuator_nuisance(nuisance));
  };
  cq.accel = window_acceleration(motion);
  for (std::size_t j = 0; j < w; ++j)
    cq.start_yaw_rad.push_back(sensors.anchors_start()[j].yaw_rad);
  cq.wheel_sin_change = motion.wheel_sin_change;
  cq.wheel_cos_change = motion.wheel_cos_change;
  cq.slowest_roll_offsets = slowest_roll_offsets(run, windows, nominal);
  return cq;
}

// Question 2, command to motion, from `command_base` (what the sensors named).
void analyse_commands(const RobotModel& nominal, const RunData& run, const SensorReplay& sensors,
                      const std::vector<Pose2>& robot_path, const MotionPeaks& peaks,
                      const RobotModel& command_base, GapResult& result) {
  const CommandReplay commands(nominal, run, sensors, robot_path);
  const QuestionReplay cq = command_question_replay(commands, sensors, nominal, run);
  result.command = analyse_question(
      Question::kCommandToMotion, command_base, cq,
      candidate_library(command_base, Question::kCommandToMotion, peaks, commands.row_period_s()),
      result.options.question);
  const ActuatorNuisance actuators = actuator_nuisance(result.command.nuisance);
  result.command_delay_s = actuators.command_delay_s;
  result.steering_yield_rad = actuators.steering_yield_rad;
  if (result.command.verdict == Verdict::kNamed) result.augmented = result.command.augmented;
  commands.path(nominal, actuators, result.replay_before);
  commands.path(result.augmented, actuators, result.replay_after);
}

}  // namespace

GapResult analyse_gap(const RobotModel& nominal, const RunData& run, const GapOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  GapResult result;
  result.options = options;
  result.nominal = nominal;
  const SensorReplay sensors(nominal, run, options.window_s);
  record_run(run, sensors, result);

  // Question 1: sensor to pose.
  const QuestionReplay sq = sensor_question_replay(sensors, nominal);
  // The robot's own dead-reckoned path (no motion-capture nuisance): the limits' starting
  // values and the command replay's view of the motion.
  std::vector<Pose2> robot_path;
  sensors.path(sim::resolve_plant(nominal), TruthNuisance{}, robot_path);
  const MotionPeaks peaks = motion_peaks(run, robot_path);
  const std::vector<Candidate> sensor_library =
      sensor_candidates(nominal, run, sensors, peaks, result.notes);
  // The motion capture fixes the robot's geometry: this question calibrates it when it names
  // nothing (QuestionOptions::calibrate).
  QuestionOptions sensor_options = options.question;
  sensor_options.calibrate = true;
  result.sensor =
      analyse_question(Question::kSensorToPose, nominal, sq, sensor_library, sensor_options);
  result.truth = sensors.truth(result.sensor.nuisance);
  result.truth_names.clear();
  for (const ParamSpec& p : sensors.nuisance()) result.truth_names.push_back(p.name);
  // The command question starts from what the sensors showed (named or calibrated), unless
  // they showed something the library cannot name.
  const RobotModel command_base =
      result.sensor.verdict != Verdict::kUnexplained ? result.sensor.augmented : nominal;
  sensors.path(sim::resolve_plant(nominal), result.truth, result.dead_reckoning_before);
  sensors.path(sim::resolve_plant(command_base), result.truth, result.dead_reckoning_after);

  // Question 2: command to motion.
  result.command_assessed = !options.sensor_only && run.has_commands;
  result.augmented = command_base;
  if (result.command_assessed) {
    analyse_commands(nominal, run, sensors, robot_path, peaks, command_base, result);
  } else {
    result.command.question = Question::kCommandToMotion;
    result.command.summary = run.has_commands
                                 ? "Command to motion: not assessed."
                                 : "Command to motion: not assessed (the run has no commands).";
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
