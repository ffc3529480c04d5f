// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/command_replay.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "swivel/motion/twist_limiter.hpp"
#include "swivel/pose_math.hpp"
#include "swivel/sim/effects.hpp"
#include "swivel/sim/open_loop.hpp"
#include "swivel/sim/world.hpp"

namespace swivel::model_gap {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Longest integration sub-step. The swpc world costs a least-squares solve per sub-step and
// is replayed hundreds of times per analysis; half a 100 Hz row keeps the first-order hold
// of the commands and the drives' lags resolved.
constexpr double kSwpcSubstepS = 0.005;
constexpr double kDifferentialSubstepS = 0.0025;

// A logged command is read as each row's value holding from halfway to the row before to
// halfway to the row after: row k holds over [span_end(k - 1), span_end(k)).
double span_end(const std::vector<double>& t, std::size_t k) {
  return k + 1 < t.size() ? 0.5 * (t[k] + t[k + 1]) : std::numeric_limits<double>::infinity();
}

// Moves `hint` (a row near `a`) to the row that holds at `a`.
void seek_row(const std::vector<double>& t, double a, std::size_t& hint) {
  while (hint + 1 < t.size() && span_end(t, hint) <= a) ++hint;
  while (hint > 0 && span_end(t, hint - 1) > a) --hint;
}

// Mean over [a, b] of a logged column so read (a < b, both within a row or two of each other).
double mean_nearest(const std::vector<double>& t, const std::vector<double>& v, double a, double b,
                    std::size_t& hint) {
  seek_row(t, a, hint);
  double sum = 0.0;
  double from = a;
  for (std::size_t k = hint; from < b && k < t.size(); ++k) {
    const double to = std::min(b, span_end(t, k));
    sum += v[k] * (to - from);
    from = to;
  }
  return sum / (b - a);
}

// Longest step of the robot's limiter in the replay: its output is sampled at each step's end.
constexpr double kLimiterStepS = 0.0005;

// Steps `limiter` through [a, b] on the logged commands as mean_nearest() reads them, each
// row's command over its own span: a ramp starts exactly where its command changed. Fed one
// mean command per step, a change larger than the limiter follows in a step started its ramp
// at that step's beginning wherever in the step it came, so the replay stood still while the
// command delay moved a change within a step and jumped at the step's edge. Where every change
// fell on an edge (rows on the ticks of the robot's path controller, with no clock jitter),
// the delay's slope was nil on one side and the fit could not move it.
void step_through(motion::TwistLimiter& limiter, const RunData& run, double a, double b,
                  std::size_t& hint) {
  seek_row(run.t_s, a, hint);
  double from = a;
  for (std::size_t k = hint; from < b && k < run.t_s.size(); ++k) {
    const double to = std::min(b, span_end(run.t_s, k));
    limiter.step(Twist2{run.cmd_vx_mps[k], run.cmd_vy_mps[k], run.cmd_wz_radps[k]}, to - from);
    from = to;
  }
}

// The limiter's output averaged over [t0, t0 + h], sampled at the end of each of its steps.
Twist2 limited_mean(motion::TwistLimiter& limiter, const RunData& run, double t0, double h,
                    std::size_t& hint) {
  // Settled on a command that holds over the sub-step (most of a run): every step would
  // leave it there.
  std::size_t whole_hint = hint;
  const Twist2 whole{mean_nearest(run.t_s, run.cmd_vx_mps, t0, t0 + h, whole_hint),
                     mean_nearest(run.t_s, run.cmd_vy_mps, t0, t0 + h, whole_hint),
                     mean_nearest(run.t_s, run.cmd_wz_radps, t0, t0 + h, whole_hint)};
  const Twist2 now = limiter.value();
  if (whole.vx_mps == now.vx_mps && whole.vy_mps == now.vy_mps && whole.wz_radps == now.wz_radps) {
    return now;
  }
  const auto steps = static_cast<int>(std::max(1.0, std::ceil(h / kLimiterStepS - 1e-9)));
  const double u = h / steps;
  Twist2 sum{0.0, 0.0, 0.0};
  for (int m = 0; m < steps; ++m) {
    const double a = t0 + m * u;
    step_through(limiter, run, a, a + u, hint);
    const Twist2 out = limiter.value();
    sum.vx_mps += out.vx_mps;
    sum.vy_mps += out.vy_mps;
    sum.wz_radps += out.wz_radps;
  }
  return Twist2{sum.vx_mps / steps, sum.vy_mps / steps, sum.wz_radps / steps};
}

// Growth factor (e-folds) of a leading caster's angle error over a window beyond which the
// window is not compared.
constexpr double kMaxSwingGrowth = 0.5;

// How hard the replay pushes a leading caster off its unstable equilibrium towards the branch
// the log shows (follow_logged_branch()); the instability does the rest.
constexpr double kBranchNudgeRadps = 0.5;

// Windows in which no caster leads its motion for long, and none has the instantaneous
// centre of rotation near its steering axis: along the path (body twist from the
// dead-reckoned poses), a caster's angle error grows at -(u . v_s) / d while it leads; where
// |v_s| < 2 d |w| it has no steady state near and turns with the body (|w| counted instead).
// The sum over a window must stay below kMaxSwingGrowth.
std::vector<char> swing_free_windows(const RobotModel& nominal, const RunData& run,
                                     const std::vector<Window>& windows,
                                     const std::vector<Pose2>& path) {
  std::vector<char> out(windows.size(), 1);
  if (run.drivetrain != DrivetrainKind::kSwpc) return out;
  const std::size_t n = run.size();
  std::vector<double> growth(n, 0.0);  // per row, the largest over modules
  for (std::size_t k = 1; k < n; ++k) {
    const double dt = run.t_s[k] - run.t_s[k - 1];
    if (!(dt > 0.0) || !std::isfinite(path[k].x_m) || !std::isfinite(path[k - 1].x_m)) continue;
    const Pose2 step = between(path[k - 1], path[k]);
    const Twist2 twist{step.x_m / dt, step.y_m / dt, step.yaw_rad / dt};
    for (std::size_t i = 0; i < nominal.modules.size(); ++i) {
      const SwpcModuleParams& m = nominal.modules[i];
      const double vx = twist.vx_mps - twist.wz_radps * m.y_m;
      const double vy = twist.vy_mps + twist.wz_radps * m.x_m;
      const double phi = run.steer_rad[i][k - 1] + m.steering_offset_rad;
      const double lambda = -(std::cos(phi) * vx + std::sin(phi) * vy) / m.caster_offset_m;
      const bool near_centre =
          std::hypot(vx, vy) < 2.0 * m.caster_offset_m * std::abs(twist.wz_radps);
      const double rate =
          std::max(std::max(0.0, lambda), near_centre ? std::abs(twist.wz_radps) : 0.0);
      growth[k] = std::max(growth[k], rate * dt);
    }
  }
  bool previous_swung = false;
  for (std::size_t j = 0; j < windows.size(); ++j) {
    double g = 0.0;
    for (std::size_t k = windows[j].a + 1; k <= windows[j].b; ++k) g += growth[k];
    const bool swung = g > kMaxSwingGrowth;
    // A caster that swung starts the next window wherever its swing left it: not compared
    // either.
    out[j] = swung || previous_swung ? 0 : 1;
    previous_swung = swung;
  }
  return out;
}

// A caster that leads its motion sits on an unstable equilibrium: the replay, free of
// disturbances, can hold it there for ever, while the robot's casters swing round (passive
// self-aligning casters always do). Where the log shows a caster in the other branch (more
// than a quarter turn from the replay's) while the replay's leads, the replay is nudged
// towards the log's side and swings the way the robot did; afterwards both are compared in
// the same branch. The swing itself is in windows that are not compared.
void follow_logged_branch(const sim::PlantParams& plant, const Twist2& twist, const RunData& run,
                          std::size_t row, const HardwareState& measured,
                          ActuatorCommand& command) {
  const double limit = plant.limits.steering_rate_radps.value_or(0.0);
  for (std::size_t i = 0; i < run.steer_rad.size(); ++i) {
    const SwpcModuleParams& m = plant.modules[i];
    const double apart = wrap_pi(run.steer_rad[i][row] - measured.steer_angle_rad[i]);
    if (std::abs(apart) <= 0.5 * std::numbers::pi) continue;
    const double phi = measured.steer_angle_rad[i] + m.steering_offset_rad;
    const double vx = twist.vx_mps - twist.wz_radps * m.y_m;
    const double vy = twist.vy_mps + twist.wz_radps * m.x_m;
    if (std::cos(phi) * vx + std::sin(phi) * vy >= 0.0) continue;  // trailing: stable
    double& rate = command.steer_rate_radps[i];
    rate += std::copysign(kBranchNudgeRadps, apart);
    if (limit > 0.0) rate = std::clamp(rate, -limit, limit);
  }
}

}  // namespace

CommandReplay::CommandReplay(const RobotModel& nominal, const RunData& run,
                             const SensorReplay& sensors, const std::vector<Pose2>& path)
    : nominal_(nominal),
      run_(&run),
      sensors_(&sensors),
      windows_(&sensors.windows()),
      swpc_(run.drivetrain == DrivetrainKind::kSwpc),
      modules_(run.module_count) {
  check_run_fits_model(nominal, run);
  const std::size_t n = run.size();
  row_period_s_ = (run.t_s.back() - run.t_s.front()) / static_cast<double>(n - 1);
  for (std::size_t i = 0; i < modules_; ++i) {
    const std::string name = swpc_ ? std::to_string(i + 1) : (i == 0 ? "l" : "r");
    channels_.push_back({"replay.wheel_" + name + "_rad", "rad", Question::kCommandToMotion,
                         ChannelKind::kWheelAngle, i});
  }
  if (swpc_) {
    for (std::size_t i = 0; i < modules_; ++i) {
      channels_.push_back({"replay.steer_" + std::to_string(i + 1) + "_rad", "rad",
                           Question::kCommandToMotion, ChannelKind::kSteerAngle, i});
    }
  }
  compared_ = swing_free_windows(nominal, run, *windows_, path);
  reseat_.assign(run.size(), 0);
  for (std::size_t j = 1; swpc_ && j < compared_.size(); ++j) {
    if (compared_[j] != 0 && compared_[j - 1] == 0) reseat_[(*windows_)[j].a] = 1;
  }
}

sim::SimOptions CommandReplay::world_options(const sim::PlantParams& plant,
                                             const ActuatorNuisance& actuators,
                                             bool move_body) const {
  sim::SimOptions options;
  options.sensor_noise = false;
  options.quantize_encoders = false;
  options.motion_capture = false;
  options.move_body = move_body;
  options.start_pose = sensors_->start_pose();
  options.substep_s = swpc_ ? kSwpcSubstepS : kDifferentialSubstepS;
  if (swpc_) {
    options.caster_forces.steering_yield_rad = actuators.steering_yield_rad;
    for (std::size_t i = 0; i < modules_; ++i) {
      options.initial_steer_rad[i] = run_->steer_rad[i][0] + plant.modules[i].steering_offset_rad;
    }
  }
  return options;
}

bool CommandReplay::simulate(const RobotModel& model, const ActuatorNuisance& actuators,
                             std::size_t end_row, bool move_body, Track& track) const {
  const double command_delay_s = actuators.command_delay_s;
  const RunData& run = *run_;
  const std::size_t n = std::min(run.size(), end_row);
  const sim::PlantParams plant = sim::resolve_plant(model);
  const double max_substep = swpc_ ? kSwpcSubstepS : kDifferentialSubstepS;
  sim::World world(model, world_options(plant, actuators, move_body));
  // The robot's controller knows only the nominal geometry; its limits are the model's.
  const sim::OpenLoopController controller(nominal_, plant.limits);
  motion::TwistLimiter limiter(plant.limits);

  track.pose.resize(run.size());
  track.wheel.resize(modules_);
  track.steer.resize(modules_);
  for (std::size_t i = 0; i < modules_; ++i) {
    track.wheel[i].resize(run.size());
    track.steer[i].resize(run.size());
  }
  HardwareState hw;
  world.read(hw);
  const auto record = [&](std::size_t k) {
    const Pose2& p = world.true_pose();
    const double previous = k == 0 ? p.yaw_rad : track.pose[k - 1].yaw_rad;
    track.pose[k] = Pose2{p.x_m, p.y_m, previous + wrap_pi(p.yaw_rad - previous)};
    for (std::size_t i = 0; i < modules_; ++i) {
      track.wheel[i][k] = hw.wheel_angle_rad[i];
    }
  };
  record(0);
  std::size_t cmd_hint = 0;
  HardwareState measured;
  measured.module_count = static_cast<std::uint32_t>(modules_);
  ActuatorCommand command;
  for (std::size_t k = 1; k < n; ++k) {
    const double dt = run.t_s[k] - run.t_s[k - 1];
    std::array<double, kMaxModules> start{};
    for (std::size_t i = 0; i < modules_; ++i) start[i] = world.sensed_steer_rad(i);
    const auto substeps = static_cast<int>(std::max(1.0, std::ceil(dt / max_substep - 1e-9)));
    const double h = dt / substeps;
    for (int s = 0; s < substeps; ++s) {
      const double t0 = run.t_s[k - 1] + s * h - command_delay_s;
      // The controller steers from the angles its encoders show (late by any sensor
      // latency), at its own rate.
      if (swpc_) {
        for (std::size_t i = 0; i < modules_; ++i)
          measured.steer_angle_rad[i] = world.steer_reading_rad(i);
      }
      const Twist2 limited = limited_mean(limiter, run, t0, h, cmd_hint);
      controller.velocity(limited, measured, command);
      if (swpc_) follow_logged_branch(plant, limited, run, k, measured, command);
      if (world.step(h, command) != Status::kOk) return false;
    }
    world.read(hw);
    record(k);
    if (swpc_) {
      for (std::size_t i = 0; i < modules_; ++i) {
        // As the log's angles are: late by any sensor latency.
        track.steer[i][k] = world.sensed_steer_rad(i) - start[i];
        // A window compared after a swing that was not starts where the log's caster is:
        // where a swing left the replay's is not what the window asks.
        if (reseat_[k] != 0) {
          const double logged = run.steer_rad[i][k] + plant.modules[i].steering_offset_rad;
          world.turn_steering(i, wrap_pi(logged - world.sensed_steer_rad(i)));
        }
      }
    }
  }
  return true;
}

bool CommandReplay::residuals(const RobotModel& model, const ActuatorNuisance& actuators,
                              std::vector<double>& out, std::size_t window_limit) const {
  const std::vector<Window>& windows = *windows_;
  const std::size_t w = windows.size();
  out.assign(channels_.size() * w, kNaN);
  const std::size_t used = std::min(w, window_limit);
  const std::size_t end_row = used == 0 ? 1 : windows[used - 1].b + 1;
  if (!simulate(model, actuators, end_row, false, track_)) return false;
  const RunData& run = *run_;
  for (std::size_t j = 0; j < used; ++j) {
    if (compared_[j] == 0) continue;
    const std::size_t a = windows[j].a;
    const std::size_t b = windows[j].b;
    std::size_t c = 0;
    for (std::size_t i = 0; i < modules_; ++i, ++c) {
      out[c * w + j] =
          (run.wheel_rad[i][b] - run.wheel_rad[i][a]) - (track_.wheel[i][b] - track_.wheel[i][a]);
    }
    if (swpc_) {
      // The sum of the rows' differences (wrapped: a caster that turned through a reversal
      // the other way round ends a turn apart and is otherwise the same).
      for (std::size_t i = 0; i < modules_; ++i, ++c) {
        double sum = 0.0;
        for (std::size_t k = a + 1; k <= b; ++k) {
          sum += wrap_pi(run.steer_rad[i][k] - run.steer_rad[i][k - 1] - track_.steer[i][k]);
        }
        out[c * w + j] = sum;
      }
    }
  }
  return std::ranges::none_of(out, [](double v) { return std::isinf(v); });
}

std::vector<double> CommandReplay::timing_variance(const RobotModel& model,
                                                   const ActuatorNuisance& actuators) const {
  const std::vector<Window>& windows = *windows_;
  const std::size_t w = windows.size();
  std::vector<double> out(channels_.size() * w, 0.0);
  Track early;
  Track late;
  ActuatorNuisance earlier = actuators;
  ActuatorNuisance later = actuators;
  earlier.command_delay_s -= 0.5 * row_period_s_;
  later.command_delay_s += 0.5 * row_period_s_;
  if (!simulate(model, earlier, run_->size(), false, early) ||
      !simulate(model, later, run_->size(), false, late)) {
    return out;
  }
  // d: how much one row's change of the channel moves when the commands come a row later.
  const auto row_shift = [&](std::size_t c, std::size_t k) {
    if (c < modules_) {
      return (late.wheel[c][k] - late.wheel[c][k - 1]) -
             (early.wheel[c][k] - early.wheel[c][k - 1]);
    }
    return wrap_pi(late.steer[c - modules_][k] - early.steer[c - modules_][k]);
  };
  for (std::size_t j = 0; j < w; ++j) {
    if (compared_[j] == 0) continue;
    for (std::size_t c = 0; c < channels_.size(); ++c) {
      double common = 0.0;
      double own = 0.0;
      for (std::size_t k = windows[j].a + 1; k <= windows[j].b; ++k) {
        const double d = row_shift(c, k);
        if (!std::isfinite(d)) continue;
        common += d;
        own += d * d;
      }
      out[c * w + j] = (common * common + own) / 12.0;
    }
  }
  return out;
}

void CommandReplay::path(const RobotModel& model, const ActuatorNuisance& actuators,
                         std::vector<Pose2>& out) const {
  out.assign(run_->size(), Pose2{kNaN, kNaN, kNaN});
  Track track;
  if (!simulate(model, actuators, run_->size(), true, track)) return;
  out = track.pose;
}

}  // namespace swivel::model_gap
