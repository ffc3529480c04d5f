// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/publish_stage.hpp"

namespace swivel::rt {

void PublishStage::publish_paused(double now_s, std::int64_t ros_stamp_ns) noexcept {
  ++state_.cycle;
  state_.stamp_s = now_s;
  state_.ros_stamp_ns = ros_stamp_ns;
  state_.odometry_twist = Twist2{};
  state_.has_twist_covariance = false;
  state_.twist_covariance = {};
  state_.has_joint_rates = false;
  state_.command_twist = Twist2{};
  snapshot_.write(state_);
}

void PublishStage::publish(const CycleReport& report, const Drivetrain& drivetrain,
                           const Hardware& hardware) noexcept {
  const HardwareState& reading = *report.reading;
  ++state_.cycle;
  state_.stamp_s = report.now_s;
  state_.ros_stamp_ns = report.ros_stamp_ns;
  state_.command_twist = report.applied;
  state_.gyro_wz_radps = report.reading_ok && reading.gyro_valid ? reading.gyro_wz_radps : 0.0;
  state_.module_count = report.module_count;
  drivetrain.module_states(std::span<ModuleState>(state_.modules.data(), report.module_count));
  state_.has_truth = hardware.ground_truth(state_.truth);
  state_.wheel_angle_rad = reading.wheel_angle_rad;
  state_.steer_angle_rad = reading.steer_angle_rad;
  state_.stopping = report.stopping;
  snapshot_.write(state_);
  run_samples_.publish(state_, report.now_s);
}

}  // namespace swivel::rt
