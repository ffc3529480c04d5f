// SPDX-License-Identifier: Apache-2.0
// swivel-lab simulate: drive the simulated robot (true model plus effects) open-loop with
// the nominal model's inverse kinematics along a standard trajectory and write a run log.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <memory>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/motion/twist_limiter.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_log.hpp"
#include "swivel/sim/effects.hpp"
#include "swivel/sim/open_loop.hpp"
#include "swivel/sim/world.hpp"
#include "trajectory.hpp"

namespace swivel::lab {
namespace {

struct SimulateOptions {
  std::string model_file;
  std::string true_model_file;
  std::vector<std::string> effects;
  std::string trajectory = "straight";
  double duration_s = 0.0;  // 0: the trajectory's own length
  double rate_hz = 100.0;
  std::uint64_t seed = 1;
  std::string noise = "realistic";
  double wheel_slip_std = 0.0;
  double lateral_scrub_std = 0.0;
  int locked_module = 1;
  double locked_steer_deg = 45.0;
  double yaw_rate_radps = 0.3;
  std::string wheel_drive = "torque";
  std::string out_file;
};

std::string format(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

int run_simulate(const SimulateOptions& o) {
  const RobotModel nominal = load_robot_model(o.model_file);
  RobotModel truth = o.true_model_file.empty() ? nominal : load_robot_model(o.true_model_file);
  if (truth.drivetrain != nominal.drivetrain || truth.module_count() != nominal.module_count()) {
    throw std::invalid_argument(o.true_model_file + ": drivetrain or module count differs from " +
                                o.model_file);
  }
  for (const std::string& e : o.effects) sim::set_effect(truth, e);

  const TrajectoryKind kind = *parse_trajectory(o.trajectory);
  const bool swpc = nominal.drivetrain == DrivetrainKind::kSwpc;
  if (needs_swpc(kind) && !swpc) {
    throw std::invalid_argument("trajectory '" + o.trajectory +
                                "' needs an omnidirectional (swpc) robot; " + o.model_file +
                                " is differential");
  }
  const double duration_s =
      o.duration_s > 0.0 ? o.duration_s : Trajectory::default_duration_s(kind);
  const Trajectory trajectory(kind, duration_s);

  sim::CalibrationMotion motion;
  if (kind == TrajectoryKind::kCalibration) {
    if (o.locked_module < 1 || static_cast<std::size_t>(o.locked_module) > nominal.modules.size()) {
      throw std::invalid_argument("--locked-module: expected 1.." +
                                  std::to_string(nominal.modules.size()) + ", got " +
                                  std::to_string(o.locked_module));
    }
    motion.locked_module = static_cast<std::size_t>(o.locked_module - 1);
    motion.locked_steer_meas_rad = o.locked_steer_deg * std::numbers::pi / 180.0;
    motion.yaw_rate_radps = o.yaw_rate_radps;
  }

  sim::SimOptions options;
  options.seed = o.seed;
  options.sensor_noise = o.noise == "realistic";
  options.nonsystematic.wheel_slip_std = o.wheel_slip_std;
  options.nonsystematic.lateral_scrub_std = o.lateral_scrub_std;
  const sim::PlantParams plant = sim::resolve_plant(truth);
  // The casters start trailing the first motion, as a robot that has just been pushed.
  options.initial_steer_rad =
      kind == TrajectoryKind::kCalibration
          ? sim::calibration_steer_angles(plant, motion)
          : sim::aligned_steer_angles(plant, trajectory.at(std::min(duration_s, 1.0)));
  sim::World world(truth, options);
  // The robot's own controller: the nominal geometry (all it knows) and the robot's true
  // limits (its firmware enforces them whatever the nominal model says).
  const sim::OpenLoopController controller(nominal, truth.limits);
  motion::TwistLimiter limiter(truth.limits);

  ActuatorCommand command;
  Twist2 calibration_twist;
  if (kind == TrajectoryKind::kCalibration &&
      !controller.calibration(motion, command, calibration_twist)) {
    throw std::invalid_argument(
        "calibration motion impossible: a free caster's steering axis "
        "lies within its caster offset of the locked pivot");
  }
  if (kind == TrajectoryKind::kCalibration && o.wheel_drive == "torque") {
    // As the paper and the daemon's procedure drive them: the wheel-rate setpoints only set
    // the pace, and each free wheel rolls as the rotation asks.
    for (ModuleDriveMode& mode : command.mode) {
      if (mode == ModuleDriveMode::kFreeSteer) mode = ModuleDriveMode::kTorque;
    }
  }

  RunLogHeader header = run_log_header(nominal);
  // The world's gyro reports the mean rate since its previous read, and it is read once a row.
  header.gyro_mean_over_row = true;
  // The world's truth is stamped on the simulation's own clock.
  header.comments.emplace_back("truth_clock: shared");
  header.comments.emplace_back("truth_frame: robot");
  header.comments.push_back("source: swivel-lab simulate, trajectory " + o.trajectory + ", rate " +
                            format(o.rate_hz) + " Hz, seed " + std::to_string(o.seed) + ", noise " +
                            o.noise);
  if (kind == TrajectoryKind::kCalibration) {
    header.comments.push_back("calibration: locked_module " + std::to_string(o.locked_module) +
                              ", locked_steer_rad " + format(motion.locked_steer_meas_rad) +
                              ", yaw_rate_radps " + format(motion.yaw_rate_radps));
  }
  RunLogWriter writer(o.out_file, header);

  const auto steps = static_cast<std::int64_t>(std::llround(duration_s * o.rate_hz));
  const double dt_s = 1.0 / o.rate_hz;
  const bool report_progress = steps >= 6000;
  std::int64_t next_report = steps / 10;
  HardwareState reading;
  for (std::int64_t k = 0; k <= steps; ++k) {
    const double t_s = static_cast<double>(k) / o.rate_hz;
    world.read(reading);
    reading.stamp_s = t_s;  // the grid, free of the sub-step sum's rounding
    Twist2 twist;
    if (kind == TrajectoryKind::kCalibration) {
      twist = calibration_twist;
    } else {
      twist = trajectory.at(t_s);
      controller.velocity(limiter.step(twist, dt_s), reading, command);
    }
    writer.write(sim::make_run_log_sample(reading, twist));
    if (k == steps) break;
    if (world.step(dt_s, command) != Status::kOk) {
      throw std::runtime_error(std::string("simulation failed at t = ") + format(t_s) +
                               " s: " + world.last_error());
    }
    if (report_progress && k == next_report) {
      std::cerr << "simulate: "
                << std::llround(100.0 * static_cast<double>(k) / static_cast<double>(steps))
                << "% (" << format(t_s) << " of " << format(duration_s) << " s)\n";
      next_report += steps / 10;
    }
  }
  writer.flush();
  const Pose2& end = world.true_pose();
  std::cout << "wrote " << o.out_file << ": " << (steps + 1) << " rows, " << nominal.name << " ("
            << (swpc ? "swpc" : "differential") << "), " << o.trajectory << " for "
            << format(duration_s) << " s; true end pose x " << format(end.x_m) << " m, y "
            << format(end.y_m) << " m, yaw " << format(end.yaw_rad) << " rad\n";
  return 0;
}

}  // namespace

void add_simulate_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Simulate a robot (true model + effects) driven open-loop with the nominal model along "
      "a trajectory, and write a run log");
  cmd->add_option("--model", options->model_file, "nominal robot model (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--true-model", options->true_model_file,
                  "robot model of the simulated world (default: the nominal model)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--effect", options->effects,
                  "hide an effect in the world: NAME.PARAM=VALUE, e.g. gyro_bias.bias_rad_s=0.006 "
                  "(repeatable)");
  cmd->add_option("--trajectory", options->trajectory, "motion")
      ->check(CLI::IsMember(trajectory_names()))
      ->capture_default_str();
  cmd->add_option("--duration", options->duration_s,
                  "length of the run, s (default: one pass of the trajectory)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--rate-hz", options->rate_hz, "log and control rate")
      ->check(CLI::Range(1.0, 10000.0))
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "random seed")->capture_default_str();
  cmd->add_option("--noise", options->noise,
                  "realistic: the model's gyro and motion-capture noise; none: noise-free "
                  "(encoders stay quantized)")
      ->check(CLI::IsMember({"realistic", "none"}))
      ->capture_default_str();
  cmd->add_option("--slip-std", options->wheel_slip_std,
                  "random wheel slip, relative 1-sigma (non-systematic; default off)")
      ->check(CLI::Range(0.0, 0.5));
  cmd->add_option("--scrub-std", options->lateral_scrub_std,
                  "random lateral scrub, fraction of speed 1-sigma (default off)")
      ->check(CLI::Range(0.0, 0.5));
  cmd->add_option("--locked-module", options->locked_module, "calibration: the locked module, 1..N")
      ->capture_default_str();
  cmd->add_option("--locked-steer-deg", options->locked_steer_deg,
                  "calibration: measured steering angle of the locked module, deg")
      ->capture_default_str();
  cmd->add_option("--yaw-rate", options->yaw_rate_radps,
                  "calibration: yaw rate about the pivot, rad/s (positive: counter-clockwise)")
      ->capture_default_str();
  cmd->add_option("--wheel-drive", options->wheel_drive,
                  "calibration: the free wheels in torque drive (they roll as the rotation asks) "
                  "or tracking constant rates from the nominal model (velocity)")
      ->check(CLI::IsMember({"torque", "velocity"}))
      ->capture_default_str();
  cmd->add_option("--out", options->out_file, "run log to write (CSV)")->required();
  cmd->callback([options, &exit_code]() { exit_code = run_simulate(*options); });
}

}  // namespace swivel::lab
