// SPDX-License-Identifier: Apache-2.0
// The bridge's subscriber thread: it waits on the readers and hands what is addressed to this
// robot to the daemon's callbacks: velocity commands (Swivel's and ROS 2's cmd_vel, stamped
// ones checked for age), motion capture, requests, and poses to set (SetPose and ROS 2's
// initialpose). The ROS 2 sensor topics and the cmd_vel type check take their samples here too.
#include <spdlog/spdlog.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <exception>
#include <string>

#include "bridge_entities.hpp"
#include "ros2_interfaces.h"
#include "swivel.h"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/cmd_vel_type_check.hpp"
#include "swivel/dds/sensor_inputs.hpp"
#include "swivel/dds/topics.hpp"
#include "take_all.hpp"

namespace swivel::dds {

void DdsBridge::subscribe_loop(const std::stop_token& stop) {
  std::array<dds_attach_t, 8> triggered{};
  while (!stop.stop_requested()) {
    const dds_return_t n =
        dds_waitset_wait(dds_->waitset, triggered.data(), triggered.size(), DDS_MSECS(200));
    if (n < 0) {
      spdlog::warn("dds: waitset failed: {}", dds_strretcode(n));
      return;
    }
    try {
      take_commands();
      take_ros2_commands();
      take_motion_capture();
      take_requests();
      take_set_poses();
      take_ros2_initialposes();
      if (dds_->sensors) dds_->sensors->take();
      if (dds_->cmd_vel_check) dds_->cmd_vel_check->take();
    } catch (const std::exception& e) {
      spdlog::warn("dds: command handling failed: {}", e.what());
    }
  }
}

void DdsBridge::deliver_command(const Twist2& twist) {
  VelocityCommand command;
  command.twist = twist;
  command.received_s = monotonic_s();
  command.sequence = ++next_command_sequence_;
  if (callbacks_.on_command && callbacks_.on_command(command)) {
    commands_received_.fetch_add(1, std::memory_order_relaxed);
  } else {
    commands_dropped_.fetch_add(1, std::memory_order_relaxed);
  }
}

void DdsBridge::take_commands() {
  take_all<swivel_msg_VelocityCommand>(
      dds_->command_reader, [this](const swivel_msg_VelocityCommand& c) {
        if (c.robot_id == nullptr || robot_id_ != c.robot_id) {
          commands_ignored_.fetch_add(1, std::memory_order_relaxed);
          return;
        }
        deliver_command({c.vx_mps, c.vy_mps, c.wz_radps});
      });
}

void DdsBridge::take_ros2_commands() {
  if (dds_->cmd_vel_reader == 0) return;
  // ROS 2 topics are per robot through their namespace: no robot id to check.
  if (!options_.ros2.cmd_vel_stamped) {
    take_all<geometry_msgs_msg_dds__Twist_>(
        dds_->cmd_vel_reader, [this](const geometry_msgs_msg_dds__Twist_& t) {
          deliver_command({t.linear.x, t.linear.y, t.angular.z});
        });
    return;
  }
  take_all<geometry_msgs_msg_dds__TwistStamped_>(
      dds_->cmd_vel_reader, [this](const geometry_msgs_msg_dds__TwistStamped_& m) {
        const auto& stamp = m.header.stamp;
        if (stamp.sec != 0 || stamp.nanosec != 0) {
          // A stamp too far from now either way (an old command, a sender's clock off) is
          // stale; a zero stamp is "now", as ros2_controllers' diff_drive_controller takes it.
          const std::int64_t stamp_ns =
              static_cast<std::int64_t>(stamp.sec) * 1'000'000'000 + stamp.nanosec;
          const double age_s = 1e-9 * static_cast<double>(realtime_now_ns() - stamp_ns);
          if (!(std::abs(age_s) <= options_.ros2.cmd_vel_max_age_s)) {
            if (commands_stale_.fetch_add(1, std::memory_order_relaxed) == 0) {
              spdlog::warn(
                  "dds: {}: dropped a TwistStamped {:.3f} s from now (more than "
                  "cmd_vel_max_age_s {} s); further ones are counted in diagnostics",
                  options_.ros2.cmd_vel_topic(), age_s, options_.ros2.cmd_vel_max_age_s);
            }
            return;
          }
        } else if (!warned_zero_stamp_) {
          warned_zero_stamp_ = true;
          spdlog::warn("dds: {}: TwistStamped with a zero stamp taken as sent now",
                       options_.ros2.cmd_vel_topic());
        }
        deliver_command({m.twist.linear.x, m.twist.linear.y, m.twist.angular.z});
      });
}

void DdsBridge::take_motion_capture() {
  take_all<swivel_msg_MotionCapture>(
      dds_->motion_capture_reader, [this](const swivel_msg_MotionCapture& m) {
        if (m.robot_id == nullptr || robot_id_ != m.robot_id) return;
        MotionCaptureSample sample;
        sample.valid = true;
        sample.stamp_s = m.stamp_s > 0.0 ? m.stamp_s : monotonic_s();
        sample.pose = {m.x_m, m.y_m, m.yaw_rad};
        if (callbacks_.on_motion_capture && callbacks_.on_motion_capture(sample)) {
          motion_captures_received_.fetch_add(1, std::memory_order_relaxed);
        }
      });
}

void DdsBridge::take_requests() {
  take_all<swivel_msg_Request>(dds_->request_reader, [this](const swivel_msg_Request& r) {
    if (r.robot_id == nullptr || robot_id_ != r.robot_id) return;
    requests_received_.fetch_add(1, std::memory_order_relaxed);
    if (!callbacks_.on_request) return;
    RequestSample sample;
    sample.verb = r.verb != nullptr ? r.verb : "";
    sample.argument = r.argument != nullptr ? r.argument : "";
    sample.request_id = r.request_id;
    callbacks_.on_request(sample);
  });
}

void DdsBridge::take_set_poses() {
  take_all<swivel_msg_SetPose>(dds_->set_pose_reader, [this](const swivel_msg_SetPose& p) {
    if (p.robot_id == nullptr || robot_id_ != p.robot_id) return;
    requests_received_.fetch_add(1, std::memory_order_relaxed);
    if (!callbacks_.on_set_pose) return;
    SetPoseSample sample;
    sample.request_id = p.request_id;
    sample.pose.pose = {p.x_m, p.y_m, p.yaw_rad};
    sample.pose.has_covariance = p.has_covariance;
    if (p.has_covariance) {
      // sigma * |sigma|: a negative sigma stays visible to the daemon's check as a negative
      // variance instead of hiding behind its square.
      const auto variance = [](double sigma) { return sigma * std::abs(sigma); };
      sample.pose.covariance = {variance(p.sigma_x_m),    0.0, 0.0, 0.0,
                                variance(p.sigma_y_m),    0.0, 0.0, 0.0,
                                variance(p.sigma_yaw_rad)};
    }
    sample.source = kSetPoseTopic;
    callbacks_.on_set_pose(sample);
  });
}

void DdsBridge::take_ros2_initialposes() {
  if (dds_->initialpose_reader == 0) return;
  take_all<geometry_msgs_msg_dds__PoseWithCovarianceStamped_>(
      dds_->initialpose_reader, [this](const geometry_msgs_msg_dds__PoseWithCovarianceStamped_& m) {
        requests_received_.fetch_add(1, std::memory_order_relaxed);
        const std::string frame = m.header.frame_id != nullptr ? m.header.frame_id : "";
        if (!frame.empty() && frame != odom_frame_) {
          spdlog::warn("{}: pose in frame '{}' ignored: swiveld estimates the pose in '{}'",
                       options_.ros2.initialpose_topic(), frame, odom_frame_);
          return;
        }
        if (!callbacks_.on_set_pose) return;
        const auto& q = m.pose.pose.orientation;
        SetPoseSample sample;
        sample.wants_reply = false;
        sample.source = options_.ros2.initialpose_topic();
        sample.pose.pose = {m.pose.pose.position.x, m.pose.pose.position.y,
                            quaternion_to_yaw(q.x, q.y, q.z, q.w)};
        // (x, y, yaw) sit at rows/columns (0, 1, 5) of ROS's 6x6; all zero means "none".
        constexpr std::array<int, 3> kIndex{0, 1, 5};
        bool any = false;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) {
            const double v = m.pose.covariance[kIndex[r] * 6 + kIndex[c]];
            sample.pose.covariance[r * 3 + c] = v;
            any = any || v != 0.0;
          }
        }
        sample.pose.has_covariance = any;
        callbacks_.on_set_pose(sample);
      });
}

}  // namespace swivel::dds
