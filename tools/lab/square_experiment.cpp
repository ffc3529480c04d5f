// SPDX-License-Identifier: Apache-2.0
#include "square_experiment.hpp"

#include <cmath>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>

#include "square_follower.hpp"
#include "swivel/pose_math.hpp"
#include "swivel/sim/effects.hpp"
#include "swivel/sim/open_loop.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"

namespace swivel::lab {

SquareRunResult run_square(const RobotModel& truth, const RobotModel& controller,
                           const SquareRunOptions& options) {
  if (truth.drivetrain != DrivetrainKind::kSwpc || controller.drivetrain != DrivetrainKind::kSwpc ||
      truth.modules.size() != controller.modules.size()) {
    throw std::invalid_argument(
        "square: true and controller models must be swpc robots with "
        "the same module count");
  }
  const std::size_t n = controller.modules.size();
  const double dt_s = 1.0 / options.rate_hz;

  sim::SimOptions sim_options;
  sim_options.seed = options.seed;
  sim_options.sensor_noise = options.sensor_noise;
  sim_options.substep_s = options.substep_s;
  sim_options.nonsystematic = options.nonsystematic;
  // Casters start trailing the first leg, as they would after a push forward.
  sim_options.initial_steer_rad =
      sim::aligned_steer_angles(sim::resolve_plant(truth), Twist2{0.2, 0.0, 0.0});
  sim::World world(truth, sim_options);
  const sim::OpenLoopController ik(controller);
  SquareFollower follower(Pose2{}, options.side_m, options.laps, options.counter_clockwise);

  SquareRunResult out;
  HardwareState prev;
  HardwareState now;
  world.read(prev);
  Pose2 odom;
  ActuatorCommand command;
  std::array<double, kMaxModules> phi{};
  std::array<double, kMaxModules> steer_rate{};
  std::array<double, kMaxModules> wheel_rate{};
  long step = 0;
  while (!follower.done() && world.time_s() < options.max_duration_s) {
    const Twist2 twist = follower.update(odom, dt_s);
    ik.velocity(twist, prev, command);
    if (world.step(dt_s, command) != Status::kOk) {
      throw std::runtime_error(std::string("square: ") + world.last_error());
    }
    world.read(now);
    // Odometry: least-squares forward kinematics of the controller's model over the step,
    // at the mid-step steering angles.
    for (std::size_t i = 0; i < n; ++i) {
      const double offset = controller.modules[i].steering_offset_rad;
      phi[i] = 0.5 * (prev.steer_angle_rad[i] + now.steer_angle_rad[i]) + offset;
      steer_rate[i] = (now.steer_angle_rad[i] - prev.steer_angle_rad[i]) / dt_s;
      wheel_rate[i] = (now.wheel_angle_rad[i] - prev.wheel_angle_rad[i]) / dt_s;
    }
    const swpc::ForwardResult fk = swpc::forward(
        std::span<const SwpcModuleParams>(controller.modules.data(), n),
        std::span<const double>(phi.data(), n), std::span<const double>(steer_rate.data(), n),
        std::span<const double>(wheel_rate.data(), n));
    if (fk.ok) odom = compose(odom, swpc::integrate_twist(fk.twist, dt_s));
    prev = now;
    ++step;
    if (options.trace_every > 0 && step % options.trace_every == 0) {
      out.trace.push_back(world.true_pose());
    }
  }
  out.finished = follower.done();
  out.duration_s = world.time_s();
  out.true_end = world.true_pose();
  out.odometry_end = odom;
  if (options.trace_every > 0) out.trace.push_back(out.true_end);
  out.position_error_m = std::hypot(out.true_end.x_m, out.true_end.y_m);
  out.heading_error_rad = std::abs(std::remainder(out.true_end.yaw_rad, 2.0 * std::numbers::pi));
  return out;
}

}  // namespace swivel::lab
