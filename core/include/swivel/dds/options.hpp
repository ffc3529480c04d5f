#pragma once
// The `dds:` section of swiveld.yaml. Start-up code: throws ConfigError.

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>

namespace swivel::dds {

/// ROS 2 compatibility: odometry as nav_msgs/Odometry on rt/<namespace>/odom,
/// geometry_msgs/Twist commands from rt/<namespace>/cmd_vel and
/// geometry_msgs/PoseWithCovarianceStamped poses from rt/<namespace>/initialpose.
struct Ros2Options {
  bool enabled = false;
  std::string ros_namespace;               ///< "" or e.g. "robot1" (no leading/trailing '/')
  std::string odom_frame_id = "odom";      ///< header.frame_id of the odometry
  std::string base_frame_id = "base_link"; ///< child_frame_id of the odometry

  /// "rt/odom" or "rt/<namespace>/odom".
  [[nodiscard]] std::string odom_topic() const;
  /// "rt/cmd_vel" or "rt/<namespace>/cmd_vel".
  [[nodiscard]] std::string cmd_vel_topic() const;
  /// "rt/initialpose" or "rt/<namespace>/initialpose".
  [[nodiscard]] std::string initialpose_topic() const;
};

struct DdsOptions {
  std::uint32_t domain_id = 0;      ///< dds.domain_id [0, 232]
  /// dds.config: Cyclone configuration file (relative to the configuration file), stored as
  /// a "file://" URI. CYCLONEDDS_URI, when set, overrides it; "" (the default) with
  /// CYCLONEDDS_URI unset: Swivel's loopback-only loopback.xml (see resolve_config()).
  std::string config_uri;
  double publish_rate_hz = 100.0;   ///< dds.publish_rate_hz: state and module states (1..1000)
  double diagnostics_rate_hz = 2.0; ///< dds.diagnostics_rate_hz (0.1..100)
  int history_depth = 1;            ///< dds.history_depth: keep-last depth of writers (1..10)
  Ros2Options ros2;                 ///< dds.ros2
};

/// Reads and validates the `dds:` mapping (null or absent: all defaults).
/// @param file        configuration file, for messages
/// @param config_dir  base of a relative dds.config path
/// @throws ConfigError naming file:line:column and key, e.g.
///         "swiveld.yaml:40:20: dds.publish_rate_hz: expected a number in [1, 1000], got 0"
DdsOptions parse_dds_options(const YAML::Node& node, const std::string& file,
                             const std::string& config_dir);

}  // namespace swivel::dds
