// SPDX-License-Identifier: Apache-2.0
#pragma once
// The `dds:` section of swiveld.yaml. Start-up code: throws ConfigError.

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "swivel/robot_model.hpp"

namespace swivel::dds {

/// A ROS 2 sensor topic the daemon subscribes to (README "External sensors"): configured
/// when its section is present; a source that goes silent stops the robot (fault
/// sensor_stale).
struct Ros2SensorTopic {
  bool enabled = false;
  std::string topic;       ///< the ROS 2 name as configured: "imu", "/mocap/robot1/pose"
  std::string dds_topic;   ///< resolved as ROS 2 does: "rt/<namespace>/imu", "rt/mocap/robot1/pose"
  double rate_hz = 100.0;  ///< the rate the driver publishes at
  double max_age_s = 0.05;       ///< newest sample older than this: stale (default 5 periods)
  double startup_grace_s = 2.0;  ///< no sample within this of the loop's start: stale
};

/// sensor_msgs/Imu as the gyro, mounted with a rotation from the IMU frame to the body
/// frame given as fixed-axis roll, pitch, yaw (a URDF joint's rpy): R = Rz(yaw) Ry(pitch)
/// Rx(roll).
struct Ros2ImuOptions : Ros2SensorTopic {
  std::array<double, 3> rotation_rpy_rad{};
};

/// Samples per expected period that make a source stale unless max_age_s is given.
inline constexpr double kDefaultMaxAgePeriods = 5.0;

/// ROS 2 compatibility (README "ROS 2 tools without a bridge"): odometry as
/// nav_msgs/Odometry on rt/<namespace>/odom, the odom -> base transform on rt/tf, joint
/// states on rt/<namespace>/joint_states, diagnostic_msgs/DiagnosticArray on rt/diagnostics,
/// geometry_msgs/TwistStamped (or Twist) commands from rt/<namespace>/cmd_vel and
/// geometry_msgs/PoseWithCovarianceStamped poses from rt/<namespace>/initialpose, all of
/// them announced as the endpoints of one ROS 2 node (ros_discovery_info).
struct Ros2Options {
  bool enabled = false;
  std::string ros_namespace;                ///< "" or e.g. "robot1" (no leading/trailing '/')
  std::string node_name = "swiveld";        ///< the ROS 2 node ROS tools list
  std::string odom_frame_id = "odom";       ///< header.frame_id of the odometry
  std::string base_frame_id = "base_link";  ///< child_frame_id of the odometry
  /// Put before odom_frame_id and base_frame_id wherever they go out or are checked, as
  /// robot_state_publisher's frame_prefix does for the URDF's links: "robot1/" gives
  /// robot1/odom and robot1/base_link. "" (default): none.
  std::string frame_prefix;
  /// Publish odom_frame_id -> base_frame_id on rt/tf (off when another node, e.g.
  /// robot_localization, publishes that transform).
  bool publish_tf = true;
  /// rt/cmd_vel carries geometry_msgs/TwistStamped (true: what Nav2 sends from Kilted on,
  /// Lyrical included, and ros2_controllers' diff_drive_controller takes since Jazzy) or
  /// geometry_msgs/Twist (false: Nav2 on Jazzy unless enable_stamped_cmd_vel is set).
  bool cmd_vel_stamped = true;
  /// TwistStamped commands whose stamp (ROS time) is further than this from the host's
  /// realtime clock, s, are dropped as stale (a zero stamp counts as "now").
  double cmd_vel_max_age_s = 0.5;
  /// rt/joint_states: one wheel joint per module, in module order, and for steered (swpc)
  /// modules one steering joint each; the daemon fills both from the robot model when the
  /// configuration names none (wheel_joints / steering_joints). Empty: no joint states.
  std::vector<std::string> wheel_joints;
  std::vector<std::string> steering_joints;
  /// Not from YAML: each module's steering offset (robot model), added to the measured
  /// steering angle so that a steering joint's position is the true angle.
  std::vector<double> steering_offsets_rad;
  /// dds.ros2.imu: the gyro from a ROS 2 IMU driver (sensor_msgs/Imu).
  Ros2ImuOptions imu;
  /// dds.ros2.mocap_pose: motion capture from a ROS 2 driver (geometry_msgs/PoseStamped).
  Ros2SensorTopic mocap_pose;

  /// frame_prefix + odom_frame_id: the odometry's frame on the wire.
  [[nodiscard]] std::string odom_frame() const { return frame_prefix + odom_frame_id; }
  /// frame_prefix + base_frame_id: the robot's frame on the wire.
  [[nodiscard]] std::string base_frame() const { return frame_prefix + base_frame_id; }
  /// The node's ROS 2 namespace: "/" or "/<namespace>".
  [[nodiscard]] std::string node_namespace() const { return "/" + ros_namespace; }
  /// "rt/odom" or "rt/<namespace>/odom".
  [[nodiscard]] std::string odom_topic() const;
  /// "rt/cmd_vel" or "rt/<namespace>/cmd_vel".
  [[nodiscard]] std::string cmd_vel_topic() const;
  /// "rt/initialpose" or "rt/<namespace>/initialpose".
  [[nodiscard]] std::string initialpose_topic() const;
  /// "rt/joint_states" or "rt/<namespace>/joint_states".
  [[nodiscard]] std::string joint_states_topic() const;
  /// "rt/tf": ROS 2's /tf is absolute (frame ids, not namespaces, tell robots apart).
  [[nodiscard]] static std::string tf_topic();
  /// "rt/diagnostics": absolute like ROS 2's /diagnostics (hardware_id names the robot).
  [[nodiscard]] static std::string diagnostics_topic();
};

struct DdsOptions {
  std::uint32_t domain_id = 0;  ///< dds.domain_id [0, 232]
  /// dds.config: Cyclone configuration file (relative to the configuration file), stored as
  /// a "file://" URI. CYCLONEDDS_URI, when set, overrides it; "" (the default) with
  /// CYCLONEDDS_URI unset: Swivel's loopback-only loopback.xml (see resolve_config()).
  std::string config_uri;
  double publish_rate_hz = 100.0;    ///< dds.publish_rate_hz: state and module states (1..1000)
  double diagnostics_rate_hz = 2.0;  ///< dds.diagnostics_rate_hz (0.1..100)
  int history_depth = 1;             ///< dds.history_depth: keep-last depth of writers (1..10)
  /// dds.run_samples_rate_hz: run samples on swivel_run_samples (what `swivelctl record`
  /// writes to a run log), 0..1000 and at most the loop rate; 0 or `off`: none.
  double run_samples_rate_hz = 100.0;
  Ros2Options ros2;  ///< dds.ros2
};

/// Reads and validates the `dds:` mapping (null or absent: all defaults).
/// @param file        configuration file, for messages
/// @param config_dir  base of a relative dds.config path
/// @throws ConfigError naming file:line:column and key, e.g.
///         "swiveld.yaml:40:20: dds.publish_rate_hz: expected a number in [1, 1000], got 0"
DdsOptions parse_dds_options(const YAML::Node& node, const std::string& file,
                             const std::string& config_dir);

/// Completes the ROS 2 joint layout from the robot model: default joint names when the
/// configuration names none (differential: left_wheel_joint, right_wheel_joint; swpc:
/// module_<i>_wheel_joint and module_<i>_steering_joint, i from 1) and the steering offsets.
/// @throws ConfigError naming `file` and the key when the named joints do not match the
///         robot's modules.
void complete_joints(const RobotModel& robot, const std::string& file, Ros2Options& ros2);

}  // namespace swivel::dds
