// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/sensor_replay.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>

#include "swivel/differential/differential_kinematics.hpp"
#include "swivel/localization/eg_odometry.hpp"
#include "swivel/pose_math.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"

namespace swivel::model_gap {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Rows on each side whose motion capture is averaged into a window's end pose.
constexpr std::size_t kAnchorHalfWidth = 5;
// Share of the stated steering rate limit from which a caster counts as held at it: a
// row's mean rate falls short of the limit by the servo's ramp into and out of it.
constexpr double kAtLimitShare = 0.9;
// How far the casters must disagree about the body's motion in a window held at the limit,
// over the run's median window, for it to count as scrubbing. Elsewhere the windows of the
// second generator's clean caster runs stay within 1.4 times the median; those where the
// sensor question saw jumps of 9-28 sigma lie at 1.9-42 times it.
constexpr double kScrubMisfitFactor = 1.5;
// How far they must disagree for a window to count as scrubbing whatever the steering does: a
// caster that steers late (actuator or steering lag, late feedback) or is held at a lower
// limit than the model states scrubs where nothing reaches the stated limit. Above the 1.4
// times the median the clean runs' windows stay within; casters steering from angles their
// sensors report 72 ms late scrub at 2.2-3.5 times it without reaching any limit.
constexpr double kScrubAloneFactor = 2.0;
// A wheel that turned by less than this (rad) may only have shown its encoder's noise.
constexpr double kEncoderNoiseRad = 1e-2;

// A caster module's steering angle (mid-row, offset applied), steering rate and wheel rate
// over row k, from the encoders.
void module_rates(const RunData& run, const SwpcModuleParams& m, std::size_t i, std::size_t k,
                  double wheel_turn, double& phi, double& steer_rate, double& wheel_rate) {
  const double dt = run.t_s[k] - run.t_s[k - 1];
  const double dphi = run.steer_rad[i][k] - run.steer_rad[i][k - 1];
  phi = run.steer_rad[i][k - 1] + 0.5 * dphi + m.steering_offset_rad;
  steer_rate = dphi / dt;
  wheel_rate = wheel_turn / dt;
}

// Per window, from the encoders: how far the casters disagree about the body's motion (the
// forward kinematics' RMS equation residual, m/s, integrated over its rows: m), the fastest
// any caster steered over one of its rows (rad/s) and whether any wheel turned by more than
// kEncoderNoiseRad over it.
struct WindowSteering {
  std::vector<double> disagreement_m;
  std::vector<double> peak_steer_rate_radps;
  std::vector<char> moving;
};

WindowSteering window_steering(const sim::PlantParams& plant, const RunData& run,
                               const std::vector<Window>& windows) {
  const std::size_t modules = run.steer_rad.size();
  std::vector<double> disagreement(run.size(), 0.0);
  std::vector<double> peak_rate(run.size(), 0.0);
  std::array<double, kMaxModules> phi{};
  std::array<double, kMaxModules> steer_rate{};
  std::array<double, kMaxModules> wheel_rate{};
  for (std::size_t k = 1; k < run.size(); ++k) {
    for (std::size_t i = 0; i < modules; ++i) {
      module_rates(run, plant.modules[i], i, k, run.wheel_rad[i][k] - run.wheel_rad[i][k - 1],
                   phi[i], steer_rate[i], wheel_rate[i]);
      peak_rate[k] = std::max(peak_rate[k], std::abs(steer_rate[i]));
    }
    const swpc::ForwardResult fit =
        swpc::forward(std::span<const SwpcModuleParams>(plant.modules.data(), modules),
                      std::span<const double>(phi.data(), modules),
                      std::span<const double>(steer_rate.data(), modules),
                      std::span<const double>(wheel_rate.data(), modules));
    if (fit.ok) disagreement[k] = fit.residual * (run.t_s[k] - run.t_s[k - 1]);
  }
  WindowSteering out{std::vector<double>(windows.size(), 0.0),
                     std::vector<double>(windows.size(), 0.0),
                     std::vector<char>(windows.size(), 0)};
  for (std::size_t j = 0; j < windows.size(); ++j) {
    for (std::size_t k = windows[j].a + 1; k <= windows[j].b; ++k) {
      out.disagreement_m[j] += disagreement[k];
      out.peak_steer_rate_radps[j] = std::max(out.peak_steer_rate_radps[j], peak_rate[k]);
    }
    for (std::size_t i = 0; i < modules; ++i) {
      const double turned =
          std::abs(run.wheel_rad[i][windows[j].b] - run.wheel_rad[i][windows[j].a]);
      if (turned > kEncoderNoiseRad) out.moving[j] = 1;
    }
  }
  return out;
}

// Per window: the casters disagreed about the motion kScrubMisfitFactor times as much as in
// the run's median moving window while some caster's steering rate over one of its rows
// reached kAtLimitShare of the limit (the model's stated one, or the fastest the run steers
// where that is lower or none is stated), or kScrubAloneFactor times as much whatever the
// steering, or kScrubMisfitFactor times as much next to such a window. The median is over the
// windows in which a wheel turned: a log that mostly stands still would otherwise have a median of
// nothing, and every moving window would count.
std::vector<char> windows_scrubbing(const RobotModel& nominal, const RunData& run,
                                    const std::vector<Window>& windows) {
  std::vector<char> out(windows.size(), 0);
  if (run.drivetrain != DrivetrainKind::kSwpc || windows.empty()) return out;
  const WindowSteering steering = window_steering(sim::resolve_plant(nominal), run, windows);
  std::vector<double> moving;
  for (std::size_t j = 0; j < windows.size(); ++j) {
    if (steering.moving[j] != 0) moving.push_back(steering.disagreement_m[j]);
  }
  if (moving.empty()) return out;
  const auto mid = moving.begin() + static_cast<std::ptrdiff_t>(moving.size() / 2);
  std::nth_element(moving.begin(), mid, moving.end());
  const double median = *mid;
  const double run_peak = *std::max_element(steering.peak_steer_rate_radps.begin(),
                                            steering.peak_steer_rate_radps.end());
  const double limit = std::min(nominal.limits.steering_rate_radps.value_or(run_peak), run_peak);
  const double at_limit = kAtLimitShare * limit;
  for (std::size_t j = 0; j < windows.size(); ++j) {
    const bool held = steering.peak_steer_rate_radps[j] >= at_limit;
    const double d = steering.disagreement_m[j];
    const bool scrubbing =
        (d >= kScrubMisfitFactor * median && held) || d >= kScrubAloneFactor * median;
    out[j] = steering.moving[j] != 0 && scrubbing ? 1 : 0;
  }
  // A scrub the window boundary cut: the neighbour of a window left out, where the casters
  // still disagree kScrubMisfitFactor times the median (past what clean runs reach).
  std::vector<char> tails = out;
  for (std::size_t j = 0; j < windows.size(); ++j) {
    const bool beside = (j > 0 && out[j - 1] != 0) || (j + 1 < windows.size() && out[j + 1] != 0);
    if (beside && steering.moving[j] != 0 &&
        steering.disagreement_m[j] >= kScrubMisfitFactor * median) {
      tails[j] = 1;
    }
  }
  return tails;
}

// Every column of `run` has a value per row (NaN where a row has none): a RunData built by
// hand, not read by load_run, may not.
void check_columns(const RunData& run) {
  const std::size_t n = run.size();
  const auto check = [&](const std::vector<double>& column, const std::string& name) {
    if (column.size() != n) {
      throw std::invalid_argument("run " + run.source + ": column " + name + " has " +
                                  std::to_string(column.size()) + " values for " +
                                  std::to_string(n) + " rows");
    }
  };
  check(run.cmd_vx_mps, "cmd_vx_mps");
  check(run.cmd_vy_mps, "cmd_vy_mps");
  check(run.cmd_wz_radps, "cmd_wz_radps");
  check(run.gyro_radps, "gyro_radps");
  check(run.truth_x_m, "truth_x_m");
  check(run.truth_y_m, "truth_y_m");
  check(run.truth_yaw_rad, "truth_yaw_rad");
  const bool swpc = run.drivetrain == DrivetrainKind::kSwpc;
  if (run.wheel_rad.size() != run.module_count ||
      (swpc && run.steer_rad.size() != run.module_count)) {
    throw std::invalid_argument("run " + run.source + " has " +
                                std::to_string(run.wheel_rad.size()) + " wheel and " +
                                std::to_string(run.steer_rad.size()) + " steering columns for " +
                                std::to_string(run.module_count) + " modules");
  }
  for (std::size_t i = 0; i < run.module_count; ++i) {
    check(run.wheel_rad[i], "wheel " + std::to_string(i + 1));
    if (swpc) check(run.steer_rad[i], "steering " + std::to_string(i + 1));
  }
}

// 1/2 w |w|: its change over a step is the integral of |w| dw/dt, the slip of sim/effects.hpp.
double half_signed_square(double w) { return 0.5 * w * std::abs(w); }

}  // namespace

void check_run_fits_model(const RobotModel& model, const RunData& run) {
  if (run.drivetrain != model.drivetrain) {
    throw std::invalid_argument(
        "run " + run.source + " is from a " +
        (run.drivetrain == DrivetrainKind::kSwpc ? "swpc" : "differential") + " robot but model " +
        model.source_file + " is not");
  }
  if (run.module_count != model.module_count()) {
    throw std::invalid_argument("run " + run.source + " has " + std::to_string(run.module_count) +
                                " modules but model " + model.source_file + " has " +
                                std::to_string(model.module_count()));
  }
  if (run.size() < 10) {
    throw std::invalid_argument("run " + run.source + " has " + std::to_string(run.size()) +
                                " samples; the workflow needs at least 10");
  }
  check_columns(run);
}

Pose2 run_start_pose(const RunData& run) {
  double sx = 0.0;
  double sy = 0.0;
  double syaw = 0.0;
  double count = 0.0;
  // A run without commands is at rest until a wheel has turned by more than an encoder's
  // worth of noise.
  const auto wheels_moved = [&run](std::size_t k) {
    return std::ranges::any_of(run.wheel_rad, [k](const std::vector<double>& wheel) {
      return std::abs(wheel[k] - wheel[0]) > kEncoderNoiseRad;
    });
  };
  for (std::size_t k = 0; k < run.size(); ++k) {
    const bool moving =
        std::isfinite(run.cmd_vx_mps[k])
            ? run.cmd_vx_mps[k] != 0.0 || run.cmd_vy_mps[k] != 0.0 || run.cmd_wz_radps[k] != 0.0
            : wheels_moved(k);
    if (count > 0.0 && (moving || run.t_s[k] - run.t_s[0] > 1.0)) break;
    if (!std::isfinite(run.truth_x_m[k])) continue;
    sx += run.truth_x_m[k];
    sy += run.truth_y_m[k];
    syaw += run.truth_yaw_rad[k];
    count += 1.0;
    if (moving) break;
  }
  if (count == 0.0) {
    throw std::invalid_argument("run " + run.source +
                                " has no motion-capture samples: nothing to compare poses with");
  }
  return Pose2{sx / count, sy / count, syaw / count};
}

SensorReplay::SensorReplay(const RobotModel& nominal, const RunData& run, double window_s)
    : run_(&run),
      swpc_(run.drivetrain == DrivetrainKind::kSwpc),
      gyro_(run.has_gyro),
      fit_time_offset_(!run.truth_clock_shared),
      fit_clock_rate_(!run.truth_clock_shared && !run.truth_clock_same_rate),
      fit_body_offset_(!run.truth_frame_is_robot),
      modules_(run.module_count) {
  check_run_fits_model(nominal, run);
  start_ = run_start_pose(run);
  const std::size_t n = run.size();
  // Smoothed wheel rates (centred over +-2 samples) keep encoder quantization out of the
  // slip correction.
  slip_h_.assign(modules_, std::vector<double>(n, 0.0));
  for (std::size_t i = 0; i < modules_; ++i) {
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t lo = k >= 2 ? k - 2 : 0;
      const std::size_t hi = std::min(n - 1, k + 2);
      const double dt = run.t_s[hi] - run.t_s[lo];
      slip_h_[i][k] =
          dt > 0.0 ? half_signed_square((run.wheel_rad[i][hi] - run.wheel_rad[i][lo]) / dt) : 0.0;
    }
  }
  const auto add = [this](const char* name, const char* unit, ChannelKind kind) {
    channels_.push_back({name, unit, Question::kSensorToPose, kind, 0});
  };
  add("dead_reckoning.dx_m", "m", ChannelKind::kPosition);
  add("dead_reckoning.dy_m", "m", ChannelKind::kPosition);
  if (gyro_) add("dead_reckoning.dyaw_gyro_rad", "rad", ChannelKind::kHeading);
  add("dead_reckoning.dyaw_encoders_rad", "rad", ChannelKind::kHeading);
  // Scales (what a fit step moves): half a degree, a centimetre, ten milliseconds. Their units
  // are unrelated to the effects': fits with them judge observability scale-free.
  if (fit_body_offset_) {
    nuisance_.push_back({"truth.yaw_offset_rad", 0.0, 1e-2, -0.2, 0.2, kNaN, true});
    nuisance_.push_back({"truth.lever_x_m", 0.0, 1e-2, -0.5, 0.5, kNaN, true});
    nuisance_.push_back({"truth.lever_y_m", 0.0, 1e-2, -0.5, 0.5, kNaN, true});
  }
  if (fit_time_offset_)
    nuisance_.push_back(
        {"truth.time_offset_s", 0.0, 1e-2, -kMaxTimeOffsetS, kMaxTimeOffsetS, kNaN, true});
  // Where between rows a sampled gyro's rate belongs: within half a row, scale a millisecond.
  if (gyro_ && !run.gyro_mean_over_row) {
    const double half_row =
        0.5 * (run.t_s.back() - run.t_s.front()) / static_cast<double>(run.size() - 1);
    nuisance_.push_back({"truth.gyro_shift_s", 0.0, 1e-3, -half_row, half_row, kNaN, true});
  }
  // Scale: a millisecond a second.
  if (fit_clock_rate_)
    nuisance_.push_back({"truth.clock_rate", 0.0, 1e-3, -kMaxClockRate, kMaxClockRate, kNaN, true});
  clock_reference_s_ = 0.5 * (run.t_s.front() + run.t_s.back());

  // The windows leave room at the ends for the longest shift a fit may try.
  const double drift =
      fit_clock_rate_ ? kMaxClockRate * 0.5 * (run.t_s.back() - run.t_s.front()) : 0.0;
  const double lead = fit_time_offset_ ? kMaxTimeOffsetS + drift : 0.0;
  const double tail = fit_time_offset_ ? kMaxTimeOffsetS + drift + kMaxLatencyS : kMaxLatencyS;
  windows_ = make_windows(run, window_s, run.t_s.front() + lead, run.t_s.back() - tail);
  motion_ = window_motion(run, windows_);
  // These anchors (the nominal dead reckoning as the path's local shape) describe the
  // windows' own motion; residuals() anchors on each replay's own path instead.
  std::vector<Pose2> shape;
  path(sim::resolve_plant(nominal), TruthNuisance{}, shape);
  for (const Window& w : windows_) {
    anchor_a_.push_back(anchor(run, shape, w.a, kAnchorHalfWidth));
    anchor_b_.push_back(anchor(run, shape, w.b, kAnchorHalfWidth));
  }
  scrubbing_ = windows_scrubbing(nominal, run, windows_);
}

TruthNuisance SensorReplay::truth(std::span<const double> values) const {
  TruthNuisance n;
  for (std::size_t i = 0; i < std::min(values.size(), nuisance_.size()); ++i) {
    const std::string& name = nuisance_[i].name;
    if (name == "truth.yaw_offset_rad") n.yaw_offset_rad = values[i];
    if (name == "truth.lever_x_m") n.lever_x_m = values[i];
    if (name == "truth.lever_y_m") n.lever_y_m = values[i];
    if (name == "truth.time_offset_s") n.time_offset_s = values[i];
    if (name == "truth.clock_rate") n.clock_rate = values[i];
    if (name == "truth.gyro_shift_s") n.gyro_shift_s = values[i];
  }
  return n;
}

double SensorReplay::gyro_mean(std::size_t k, double gyro_shift_s) const {
  const RunData& run = *run_;
  // The logged value where the log declares row means, else the trapezoid of the readings at
  // the row's ends (swivel/run_log.hpp). At a step of the rate within the row its error is at
  // most half the step times dt, either way; the reading at t[k] taken as the mean would turn
  // every step early, all one way.
  if (run.gyro_mean_over_row) return run.gyro_radps[k];
  if (gyro_shift_s == 0.0) return 0.5 * (run.gyro_radps[k - 1] + run.gyro_radps[k]);
  // Readings standing for the rate at t[j] + shift, joined by straight lines: the mean over
  // (t[k-1], t[k]] is that of the readings' own line over the interval moved back by the
  // shift, which reaches into the neighbouring row (or holds the first and last readings).
  const std::vector<double>& t = run.t_s;
  const std::vector<double>& w = run.gyro_radps;
  const double a = t[k - 1] - gyro_shift_s;
  const double b = t[k] - gyro_shift_s;
  const auto value = [&t, &w](std::size_t j, double at) {  // line from j to j + 1
    if (j + 1 >= t.size()) return w.back();
    const double f = std::clamp((at - t[j]) / (t[j + 1] - t[j]), 0.0, 1.0);
    return w[j] + f * (w[j + 1] - w[j]);
  };
  double sum = 0.0;
  std::size_t j = k >= 3 ? k - 3 : 0;
  for (; j + 1 < t.size() && t[j] < b; ++j) {
    const double lo = std::max(a, t[j]);
    const double hi = std::min(b, t[j + 1]);
    if (hi > lo) sum += 0.5 * (value(j, lo) + value(j, hi)) * (hi - lo);
  }
  if (a < t.front()) sum += w.front() * (std::min(b, t.front()) - a);
  if (b > t.back()) sum += w.back() * (b - std::max(a, t.back()));
  return sum / (b - a);
}

bool SensorReplay::integrate(const sim::PlantParams& plant, const Pose2& start, std::size_t end_row,
                             double gyro_shift_s) const {
  const RunData& run = *run_;
  const std::size_t n = std::min(run.size(), end_row);
  localization::EgConfig config;
  // Without a gyro the heading is the encoders' (the E/G odometry's alternative).
  config.heading_source =
      gyro_ ? localization::HeadingSource::kGyro : localization::HeadingSource::kEncoders;
  config.gyro_scale = plant.sensors.gyro.scale;
  config.gyro_bias_radps = plant.sensors.gyro.bias_rad_s;
  localization::EgOdometry eg(config);
  eg.reset(start);
  track_.resize(run.size());
  encoder_yaw_.resize(run.size());
  track_[0] = start;
  encoder_yaw_[0] = 0.0;
  const double g = plant.slip_gain_per_radps2;
  std::array<double, kMaxModules> dpsi{};
  std::array<double, kMaxModules> phi{};
  std::array<double, kMaxModules> steer_rate{};
  std::array<double, kMaxModules> wheel_rate{};
  for (std::size_t k = 1; k < n; ++k) {
    const double dt = run.t_s[k] - run.t_s[k - 1];
    for (std::size_t i = 0; i < modules_; ++i) {
      // The contact point rolls less than the wheel turns while it speeds up.
      dpsi[i] =
          run.wheel_rad[i][k] - run.wheel_rad[i][k - 1] - g * (slip_h_[i][k] - slip_h_[i][k - 1]);
    }
    Pose2 delta;
    if (!swpc_) {
      delta = differential::forward_increment(sim::effective_differential(plant, dpsi[0], dpsi[1]),
                                              dpsi[0], dpsi[1]);
    } else {
      for (std::size_t i = 0; i < modules_; ++i) {
        module_rates(run, plant.modules[i], i, k, dpsi[i], phi[i], steer_rate[i], wheel_rate[i]);
      }
      const swpc::ForwardResult fit =
          swpc::forward(std::span<const SwpcModuleParams>(plant.modules.data(), modules_),
                        std::span<const double>(phi.data(), modules_),
                        std::span<const double>(steer_rate.data(), modules_),
                        std::span<const double>(wheel_rate.data(), modules_));
      if (!fit.ok) return false;
      delta = swpc::integrate_twist(fit.twist, dt);
    }
    const double rate = gyro_ ? gyro_mean(k, gyro_shift_s) : 0.0;
    if (!eg.step(delta, dt, rate, gyro_)) return false;
    const Pose2 p = eg.pose();
    track_[k] = Pose2{p.x_m, p.y_m, eg.unwrapped_yaw_rad()};
    encoder_yaw_[k] = encoder_yaw_[k - 1] + delta.yaw_rad;
  }
  return true;
}

Pose2 SensorReplay::pose_at(double t_s) const {
  const std::vector<double>& t = run_->t_s;
  if (t_s <= t.front()) return track_.front();
  if (t_s >= t.back()) return track_.back();
  const auto it = std::upper_bound(t.begin(), t.end(), t_s);
  const auto k = static_cast<std::size_t>(it - t.begin());
  const double f = (t_s - t[k - 1]) / (t[k] - t[k - 1]);
  return lerp(track_[k - 1], track_[k], f);
}

double SensorReplay::encoder_yaw_at(double t_s) const {
  const std::vector<double>& t = run_->t_s;
  if (t_s <= t.front()) return encoder_yaw_.front();
  if (t_s >= t.back()) return encoder_yaw_.back();
  const auto it = std::upper_bound(t.begin(), t.end(), t_s);
  const auto k = static_cast<std::size_t>(it - t.begin());
  const double f = (t_s - t[k - 1]) / (t[k] - t[k - 1]);
  return encoder_yaw_[k - 1] + f * (encoder_yaw_[k] - encoder_yaw_[k - 1]);
}

bool SensorReplay::residuals(const sim::PlantParams& plant, const TruthNuisance& truth,
                             std::vector<double>& out, std::size_t window_limit) const {
  const std::size_t w = windows_.size();
  out.assign(channels_.size() * w, kNaN);
  const std::size_t used = std::min(w, window_limit);
  // Rows up to the last window's end and the rows its anchor averages, plus the shift.
  std::size_t end_row = run_->size();
  if (used > 0 && used < w) {
    const double last = run_->t_s[windows_[used - 1].b];
    const double shift = shift_at(plant.sensor_delay_s, truth, last);
    end_row = std::min(run_->size(), windows_[used - 1].b + 1 + kAnchorHalfWidth);
    const double until = run_->t_s[end_row - 1];
    while (end_row < run_->size() && run_->t_s[end_row - 1] < until + std::max(shift, 0.0))
      ++end_row;
  }
  if (!integrate(plant, start_, end_row, truth.gyro_shift_s)) return false;
  // Encoders and gyro lag the robot by the delay, motion capture by its clock offset: the
  // motion capture's sample at t shows where the encoders put the robot at t + delay - offset.
  // The tracked body B sits on the robot, so the robot's own change between two samples is
  // B (Ma^-1 Mb) B^-1.
  const Pose2 body = truth.body();
  const Pose2 body_inverse = inverse(body);
  const std::vector<double>& t = run_->t_s;
  const std::size_t encoder_channel = gyro_ ? 3 : 2;
  track_shape(plant, truth, used);
  for (std::size_t j = 0; j < used; ++j) {
    const Pose2 ma = anchor(*run_, shape_, windows_[j].a, kAnchorHalfWidth);
    const Pose2 mb = anchor(*run_, shape_, windows_[j].b, kAnchorHalfWidth);
    if (!std::isfinite(ma.x_m) || !std::isfinite(mb.x_m) || scrubbing_[j] != 0) continue;
    const double ta = t[windows_[j].a] + shift_at(plant.sensor_delay_s, truth, t[windows_[j].a]);
    const double tb = t[windows_[j].b] + shift_at(plant.sensor_delay_s, truth, t[windows_[j].b]);
    const Pose2 measured = compose(compose(body, between(ma, mb)), body_inverse);
    const Pose2 predicted = between(pose_at(ta), pose_at(tb));
    const double encoder_turn = encoder_yaw_at(tb) - encoder_yaw_at(ta);
    out[0 * w + j] = measured.x_m - predicted.x_m;
    out[1 * w + j] = measured.y_m - predicted.y_m;
    if (gyro_) out[2 * w + j] = (mb.yaw_rad - ma.yaw_rad) - (predicted.yaw_rad);
    out[encoder_channel * w + j] = (mb.yaw_rad - ma.yaw_rad) - encoder_turn;
  }
  return std::ranges::none_of(out, [](double v) { return std::isinf(v); });
}

void SensorReplay::track_shape(const sim::PlantParams& plant, const TruthNuisance& truth,
                               std::size_t windows) const {
  const std::vector<double>& t = run_->t_s;
  const Pose2 body = truth.body();
  shape_.assign(run_->size(), Pose2{kNaN, kNaN, kNaN});
  const auto fill_around = [&](std::size_t row) {
    const std::size_t lo = row >= kAnchorHalfWidth ? row - kAnchorHalfWidth : 0;
    const std::size_t hi = std::min(run_->size() - 1, row + kAnchorHalfWidth);
    for (std::size_t k = lo; k <= hi; ++k) {
      if (std::isfinite(shape_[k].x_m)) continue;
      shape_[k] = compose(pose_at(t[k] + shift_at(plant.sensor_delay_s, truth, t[k])), body);
    }
  };
  for (std::size_t j = 0; j < windows; ++j) {
    fill_around(windows_[j].a);
    fill_around(windows_[j].b);
  }
}

void SensorReplay::path(const sim::PlantParams& plant, const TruthNuisance& truth,
                        std::vector<Pose2>& out) const {
  const std::size_t n = run_->size();
  out.assign(n, Pose2{kNaN, kNaN, kNaN});
  const Pose2 body = truth.body();
  // The robot starts where the tracked body at rest says it is.
  if (!integrate(plant, compose(start_, inverse(body)), n, truth.gyro_shift_s)) return;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = run_->t_s[k];
    const Pose2 robot = pose_at(t + shift_at(plant.sensor_delay_s, truth, t));
    // Keep the unwrapped heading: compose() leaves the sum unwrapped.
    out[k] = compose(robot, body);
  }
}

}  // namespace swivel::model_gap
