// SPDX-License-Identifier: Apache-2.0
// The state as ROS 2 tools read it, written by the bridge's publisher thread with each
// RobotState: nav_msgs Odometry, the odom -> base transform on tf and the wheel and steering
// joints' JointState, in the frames and names of dds.ros2; and the yaw <-> quaternion
// conversions between Swivel's poses and ROS 2's.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include "bridge_entities.hpp"
#include "ros2_interfaces.h"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/ros_covariance.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/rt/clock_offset.hpp"

namespace swivel::dds {

void yaw_to_quaternion(double yaw_rad, double& x, double& y, double& z, double& w) noexcept {
  x = 0.0;
  y = 0.0;
  z = std::sin(0.5 * yaw_rad);
  w = std::cos(0.5 * yaw_rad);
}

double quaternion_to_yaw(double x, double y, double z, double w) noexcept {
  const double norm = std::sqrt(x * x + y * y + z * z + w * w);
  if (!std::isfinite(norm) || std::abs(norm - 1.0) > 0.01) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

namespace {

// Odometry and the transform share their header and frames: odom -> base at the stamp.
template <class Stamped>
void stamp_odom_to_base(Stamped& m, const rt::RosTime& stamp, const std::string& odom_frame,
                        const std::string& base_frame) noexcept {
  m.header.stamp.sec = stamp.sec;
  m.header.stamp.nanosec = stamp.nanosec;
  m.header.frame_id = c_str(odom_frame);
  m.child_frame_id = c_str(base_frame);
}

}  // namespace

void DdsBridge::publish_ros2_state(const StateSnapshot& s) {
  // ROS time of the same instant as stamp_s, mapped by the loop (rt::ClockOffset).
  const rt::RosTime ros_stamp = rt::to_ros_time(s.ros_stamp_ns);
  if (dds_->odom_writer != 0) {
    nav_msgs_msg_dds__Odometry_ odom{};
    stamp_odom_to_base(odom, ros_stamp, odom_frame_, base_frame_);
    odom.pose.pose.position.x = s.estimate.pose.x_m;
    odom.pose.pose.position.y = s.estimate.pose.y_m;
    auto& q = odom.pose.pose.orientation;
    yaw_to_quaternion(s.estimate.pose.yaw_rad, q.x, q.y, q.z, q.w);
    to_ros_covariance(s.estimate.has_covariance ? &s.estimate.covariance : nullptr,
                      odom.pose.covariance);
    odom.twist.twist.linear.x = s.odometry_twist.vx_mps;
    odom.twist.twist.linear.y = s.odometry_twist.vy_mps;
    odom.twist.twist.angular.z = s.odometry_twist.wz_radps;
    to_ros_covariance(s.has_twist_covariance ? &s.twist_covariance : nullptr,
                      odom.twist.covariance);
    check(dds_write(dds_->odom_writer, &odom), "dds_write(odom)");
  }

  if (dds_->tf_writer != 0) {
    geometry_msgs_msg_dds__TransformStamped_ transform{};
    stamp_odom_to_base(transform, ros_stamp, odom_frame_, base_frame_);
    transform.transform.translation.x = s.estimate.pose.x_m;
    transform.transform.translation.y = s.estimate.pose.y_m;
    auto& q = transform.transform.rotation;
    yaw_to_quaternion(s.estimate.pose.yaw_rad, q.x, q.y, q.z, q.w);
    tf2_msgs_msg_dds__TFMessage_ tf{};
    borrow(tf.transforms, &transform, 1);
    check(dds_write(dds_->tf_writer, &tf), "dds_write(tf)");
  }

  if (dds_->joint_states_writer != 0) {
    // Wheel joints, then steering joints, in module order: positions at stamp_s, velocities
    // the rates fitted over the twist window (absent until the loop has them).
    const std::uint32_t modules = std::min(s.module_count, kMaxModules);
    const auto wheels = std::min<std::size_t>(options_.ros2.wheel_joints.size(), modules);
    const auto steering = std::min<std::size_t>(options_.ros2.steering_joints.size(), modules);
    std::array<char*, std::size_t{2} * kMaxModules> names{};
    std::array<double, std::size_t{2} * kMaxModules> position{};
    std::array<double, std::size_t{2} * kMaxModules> velocity{};
    std::size_t n = 0;
    for (std::size_t i = 0; i < wheels; ++i, ++n) {
      names[n] = c_str(options_.ros2.wheel_joints[i]);
      position[n] = s.wheel_angle_rad[i];
      velocity[n] = s.wheel_rate_radps[i];
    }
    for (std::size_t i = 0; i < steering; ++i, ++n) {
      names[n] = c_str(options_.ros2.steering_joints[i]);
      const double offset = i < options_.ros2.steering_offsets_rad.size()
                                ? options_.ros2.steering_offsets_rad[i]
                                : 0.0;
      position[n] = s.steer_angle_rad[i] + offset;
      velocity[n] = s.steer_rate_radps[i];
    }
    sensor_msgs_msg_dds__JointState_ joints{};
    joints.header.stamp.sec = ros_stamp.sec;
    joints.header.stamp.nanosec = ros_stamp.nanosec;
    joints.header.frame_id = c_str("");
    const auto length = static_cast<std::uint32_t>(n);
    borrow(joints.name, names.data(), length);
    borrow(joints.position, position.data(), length);
    borrow(joints.velocity, velocity.data(), s.has_joint_rates ? length : 0);
    check(dds_write(dds_->joint_states_writer, &joints), "dds_write(joint states)");
  }
}

}  // namespace swivel::dds
