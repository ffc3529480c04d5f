// SPDX-License-Identifier: Apache-2.0
#include "gap_fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "swivel/motion/twist_limiter.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/sim/open_loop.hpp"
#include "swivel/sim/world.hpp"

namespace swivel::model_gap::testing {
namespace {

// Piecewise-linear profile through (time, value) knots; ramps keep accelerations finite.
double knots(double t, std::initializer_list<std::pair<double, double>> points) {
  auto prev = *points.begin();
  for (const auto& p : points) {
    if (t <= p.first) {
      if (p.first <= prev.first) return p.second;
      return prev.second + (t - prev.first) / (p.first - prev.first) * (p.second - prev.second);
    }
    prev = p;
  }
  return prev.second;
}

}  // namespace

RobotModel robot(const std::string& name) {
  const char* dir = std::getenv("SWIVEL_SOURCE_DIR");
  const std::string root = dir != nullptr ? dir : SWIVEL_SOURCE_DIR_FALLBACK;
  return load_robot_model(root + "/config/robots/" + name + ".yaml");
}

Twist2 pattern_command(double t_s, bool holonomic) {
  const double t = std::fmod(t_s, 20.0);
  Twist2 c;
  c.vx_mps = knots(t, {{1.5, 0.0},
                       {2.5, 0.4},
                       {6.0, 0.4},
                       {6.5, 0.3},
                       {9.0, 0.3},
                       {9.5, 0.2},
                       {10.5, 0.2},
                       {11.0, 0.0},
                       {14.0, 0.0},
                       {14.5, 0.5},
                       {17.0, 0.5},
                       {18.0, 0.0}});
  c.wz_radps = knots(t, {{6.0, 0.0},
                         {6.5, 0.6},
                         {8.5, 0.6},
                         {9.0, 0.0},
                         {11.0, 0.0},
                         {11.5, -0.8},
                         {13.5, -0.8},
                         {14.0, 0.0},
                         {14.5, 0.2},
                         {17.0, 0.2},
                         {17.5, 0.0}});
  if (holonomic) {
    c.vy_mps = knots(t, {{2.5, 0.0},
                         {3.0, 0.15},
                         {5.5, 0.15},
                         {6.0, 0.0},
                         {14.0, 0.0},
                         {14.5, -0.25},
                         {16.5, -0.25},
                         {17.0, 0.0}});
  }
  return c;
}

RunLog simulate_run(const RobotModel& nominal, const RobotModel& truth, double duration_s,
                    std::uint64_t seed, double rate_hz) {
  sim::SimOptions options;
  options.seed = seed;
  const bool swpc = nominal.drivetrain == DrivetrainKind::kSwpc;
  // The casters start trailing the first motion, as `swivel-lab simulate` starts them.
  options.initial_steer_rad =
      sim::aligned_steer_angles(sim::resolve_plant(truth), pattern_command(2.0, swpc));
  sim::World world(truth, options);
  RunLog log;
  log.source = "simulated";
  log.header = run_log_header(nominal);
  log.header.comments.emplace_back("truth_clock: shared");  // the world's own truth
  log.header.comments.emplace_back("truth_frame: robot");
  log.header.gyro_mean_over_row = true;  // one read a row: the world's mean since the last
  const auto rows = static_cast<std::size_t>(std::llround(duration_s * rate_hz)) + 1;
  const double dt = 1.0 / rate_hz;
  // The robot's controller runs at 1 kHz on the continuously changing command, as a real
  // drive does; rows sample it (swivel/run_log.hpp).
  const auto control_steps = static_cast<int>(std::max(1.0, std::round(dt / 0.001)));
  const double h = dt / control_steps;
  const sim::OpenLoopController controller(nominal, truth.limits);
  const sim::PlantParams plant = sim::resolve_plant(truth);
  HardwareState hw;
  HardwareState measured;
  measured.module_count = static_cast<std::uint32_t>(nominal.module_count());
  ActuatorCommand command;
  for (std::size_t k = 0; k < rows; ++k) {
    const double t = static_cast<double>(k) * dt;
    world.read(hw);
    hw.stamp_s = t;
    log.samples.push_back(sim::make_run_log_sample(hw, pattern_command(t, swpc)));
    if (k + 1 == rows) break;
    for (int s = 0; s < control_steps; ++s) {
      for (std::size_t i = 0; i < nominal.module_count(); ++i) {
        measured.steer_angle_rad[i] =
            world.true_steer_rad(i) - plant.modules[i].steering_offset_rad;
      }
      controller.velocity(pattern_command(t + s * h, swpc), measured, command);
      if (world.step(h, command) != Status::kOk) throw std::runtime_error(world.last_error());
    }
  }
  return log;
}

RunLog record_like_swiveld(const RobotModel& nominal, const RobotModel& truth,
                           const std::vector<ScriptStep>& script, double duration_s,
                           std::uint64_t seed, double script_phase_s, double rate_hz) {
  constexpr double kCycleS = 0.001;
  double period_s = 0.0;
  for (const ScriptStep& step : script) period_s += step.duration_s;
  if (script.empty() || !(period_s > 0.0)) throw std::invalid_argument("empty script");
  const auto script_at = [&](double t) {
    double u = std::fmod(t + script_phase_s, period_s);
    for (const ScriptStep& step : script) {
      if (u < step.duration_s) return step.twist;
      u -= step.duration_s;
    }
    return script.back().twist;
  };
  sim::SimOptions options;
  options.seed = seed;
  sim::World world(truth, options);
  const sim::OpenLoopController controller(nominal);
  motion::TwistLimiter limiter(nominal.limits);
  RunLog log;
  log.source = "recorded like swiveld";
  log.header = run_log_header(nominal);
  log.header.comments.emplace_back("truth_clock: shared");  // the simulated world's truth
  log.header.comments.emplace_back("truth_frame: robot");
  const auto cycles_per_row = static_cast<std::int64_t>(std::llround(1.0 / (rate_hz * kCycleS)));
  const auto cycles = static_cast<std::int64_t>(std::llround(duration_s / kCycleS));
  HardwareState hw;
  ActuatorCommand command;
  bool have_truth = false;
  Pose2 truth_pose;
  for (std::int64_t c = 0; c <= cycles; ++c) {
    const double t = static_cast<double>(c) * kCycleS;
    world.read(hw);
    // A motion-capture sample is reported by one read only: a row keeps the latest since the
    // row before, as the daemon's state does.
    if (hw.motion_capture.valid) {
      have_truth = true;
      truth_pose = hw.motion_capture.pose;
    }
    const Twist2 twist = script_at(t);
    if (c % cycles_per_row == 0) {
      hw.stamp_s = t;
      RunLogSample row = sim::make_run_log_sample(hw, twist);
      row.has_truth = have_truth;
      row.truth = truth_pose;
      have_truth = false;
      log.samples.push_back(row);
    }
    if (c == cycles) break;
    controller.velocity(limiter.step(twist, kCycleS), hw, command);
    if (world.step(kCycleS, command) != Status::kOk) throw std::runtime_error(world.last_error());
  }
  return log;
}

void add_eccentric_wheel(RunLog& log, double amplitude) {
  // Ground travel r (psi + a sin psi) equals the simulated r psi_sim: solve for the angle the
  // encoder would have read (Newton, from the simulated angle).
  for (RunLogSample& s : log.samples) {
    const double target = s.wheel_rad[0];
    double psi = target;
    for (int it = 0; it < 20; ++it) {
      psi -= (psi + amplitude * std::sin(psi) - target) / (1.0 + amplitude * std::cos(psi));
    }
    s.wheel_rad[0] = psi;
  }
}

}  // namespace swivel::model_gap::testing
