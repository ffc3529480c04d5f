// SPDX-License-Identifier: Apache-2.0
#pragma once
// Shared helpers of the simulator tests: robot models built in code and dead reckoning
// through the kinematics libraries' forward functions.

#include <cmath>
#include <numbers>
#include <span>
#include <utility>

#include "swivel/differential/differential_kinematics.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"
#include "swivel/types.hpp"

namespace swivel::sim::test {

inline RobotModel docent() {
  RobotModel m;
  m.name = "docent";
  m.drivetrain = DrivetrainKind::kDifferential;
  m.differential = {0.075, 0.075, 0.40};
  m.sensors.gyro = {1.0, 0.0, 0.002};
  return m;
}

/// The paper's four-caster robot with its design values.
inline RobotModel swpc4() {
  RobotModel m;
  m.name = "swpc4";
  m.drivetrain = DrivetrainKind::kSwpc;
  const double xs[] = {0.215, 0.215, -0.215, -0.215};
  const double ys[] = {0.125, -0.125, -0.125, 0.125};
  for (int i = 0; i < 4; ++i) m.modules.push_back({xs[i], ys[i], 0.0, 0.020, 0.055});
  m.sensors.gyro = {1.0, 0.0, 0.002};
  return m;
}

inline double wrap(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

inline Pose2 compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.yaw_rad);
  const double s = std::sin(a.yaw_rad);
  return {a.x_m + c * b.x_m - s * b.y_m, a.y_m + s * b.x_m + c * b.y_m, a.yaw_rad + b.yaw_rad};
}

/// Encoder dead reckoning with the nominal model (yaw unwrapped).
class Odometry {
 public:
  Odometry(RobotModel nominal, const Pose2& start) : model_(std::move(nominal)), pose_(start) {}

  void update(const HardwareState& prev, const HardwareState& cur) {
    const double dt = cur.stamp_s - prev.stamp_s;
    if (!(dt > 0.0)) return;
    if (model_.drivetrain == DrivetrainKind::kDifferential) {
      pose_ =
          compose(pose_, differential::forward_increment(
                             model_.differential, cur.wheel_angle_rad[0] - prev.wheel_angle_rad[0],
                             cur.wheel_angle_rad[1] - prev.wheel_angle_rad[1]));
      return;
    }
    const std::size_t n = model_.modules.size();
    double phi[kMaxModules];
    double steer[kMaxModules];
    double wheel[kMaxModules];
    for (std::size_t i = 0; i < n; ++i) {
      // Mid-interval steering angle: the rates hold over the interval.
      phi[i] = 0.5 * (prev.steer_angle_rad[i] + cur.steer_angle_rad[i]) +
               model_.modules[i].steering_offset_rad;
      steer[i] = (cur.steer_angle_rad[i] - prev.steer_angle_rad[i]) / dt;
      wheel[i] = (cur.wheel_angle_rad[i] - prev.wheel_angle_rad[i]) / dt;
    }
    const swpc::ForwardResult r =
        swpc::forward(model_.modules, std::span<const double>(phi, n),
                      std::span<const double>(steer, n), std::span<const double>(wheel, n));
    if (r.ok) pose_ = compose(pose_, swpc::integrate_twist(r.twist, dt));
  }

  [[nodiscard]] const Pose2& pose() const { return pose_; }

 private:
  RobotModel model_;
  Pose2 pose_;
};

}  // namespace swivel::sim::test
