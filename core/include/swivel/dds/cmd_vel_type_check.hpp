// SPDX-License-Identifier: Apache-2.0
#pragma once
// A ROS 2 node that publishes cmd_vel as geometry_msgs/Twist does not match a reader of
// TwistStamped (and the other way round): DDS matches by type name, so the robot does not
// move and neither side says why. This check reads the DDS built-in publication topic for
// writers on the daemon's cmd_vel topic whose type is not the one it reads, logs each such
// type once, and says what to set for the diagnostics and `swivelctl status`. Not real-time
// safe: take() runs on the bridge's subscriber thread, warning() on any thread.

#include <dds/dds.h>

#include <map>
#include <mutex>
#include <set>
#include <string>

namespace swivel::dds {

class CmdVelTypeCheck {
 public:
  /// @param dds_topic  the cmd_vel topic on the wire, "rt/cmd_vel" or "rt/<ns>/cmd_vel"
  /// @param stamped    true when the daemon reads geometry_msgs/TwistStamped, false: Twist
  /// @throws DdsError when the built-in reader cannot be created
  CmdVelTypeCheck(dds_entity_t participant, std::string dds_topic, bool stamped);

  /// The built-in publication reader, for the caller's waitset.
  [[nodiscard]] dds_entity_t reader() const { return reader_; }

  /// Takes the discovered and departed publications (subscriber thread).
  void take();

  /// "" while every cmd_vel publisher has the daemon's type; else, per foreign type, e.g.
  /// "a TwistStamped publisher on /cmd_vel; set dds.ros2.cmd_vel_stamped: true".
  [[nodiscard]] std::string warning() const;

  /// The ROS 2 name of a DDS type name: "geometry_msgs::msg::dds_::Twist_" gives
  /// "geometry_msgs/msg/Twist"; other names are returned as they are.
  static std::string ros_type_name(const std::string& dds_type_name);

 private:
  std::string dds_topic_;
  std::string ros_topic_;  ///< "/cmd_vel" or "/<ns>/cmd_vel"
  bool stamped_;
  dds_entity_t reader_ = 0;
  mutable std::mutex mutex_;
  std::map<dds_instance_handle_t, std::string> foreign_;  ///< live publications: DDS type
  std::set<std::string> logged_;                          ///< foreign types logged so far
};

}  // namespace swivel::dds
