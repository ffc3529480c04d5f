// SPDX-License-Identifier: Apache-2.0
#include "swivel/dds/options.hpp"

#include <cmath>
#include <filesystem>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/dds/topics.hpp"

namespace swivel::dds {

namespace {

std::string ros2_topic(const std::string& ros_namespace, const char* name) {
  return ros_namespace.empty() ? std::string("rt/") + name : "rt/" + ros_namespace + "/" + name;
}

bool valid_ros_name(const std::string& name) {
  // ROS 2 names: alphanumerics and underscores, '/' separated, no empty tokens, no leading
  // digit in a token.
  bool token_start = true;
  for (const char c : name) {
    if (c == '/') {
      if (token_start) return false;
      token_start = true;
      continue;
    }
    const bool alpha = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
    const bool digit = c >= '0' && c <= '9';
    if (!alpha && !digit) return false;
    if (token_start && digit) return false;
    token_start = false;
  }
  return name.empty() || !token_start;
}

// A sensor topic's ROS 2 name, resolved the way ROS 2 does: a relative name under the
// namespace, an absolute one ("/imu") as it is.
std::string resolve_topic(ParamReader& reader, const std::string& ros_namespace,
                          const std::string& name) {
  const bool absolute = !name.empty() && name.front() == '/';
  const std::string bare = absolute ? name.substr(1) : name;
  if (bare.empty() || !valid_ros_name(bare)) {
    reader.fail("topic",
                "expected a ROS 2 topic name (letters, digits, '_', '/'; '/' first for "
                "an absolute one), got '" +
                    name + "'");
  }
  return absolute ? "rt/" + bare : ros2_topic(ros_namespace, bare.c_str());
}

void parse_sensor_topic(ParamReader& reader, const std::string& ros_namespace,
                        const char* default_topic, Ros2SensorTopic& out) {
  out.enabled = true;
  out.topic =
      default_topic != nullptr ? reader.string_or("topic", default_topic) : reader.string("topic");
  out.dds_topic = resolve_topic(reader, ros_namespace, out.topic);
  out.rate_hz = reader.number_or("rate_hz", 100.0, 0.1, 10000.0);
  out.max_age_s = reader.number_or("max_age_s", kDefaultMaxAgePeriods / out.rate_hz, 0.001, 60.0);
  out.startup_grace_s = reader.number_or("startup_grace_s", 2.0, 0.0, 600.0);
}

void parse_rotation(ParamReader& reader, std::array<double, 3>& rpy_rad) {
  const YAML::Node list = reader.sequence("rotation_rpy_rad");
  if (list.size() == 0) return;  // absent: the IMU frame is the body frame
  const auto wrong = [&](const std::string& got) {
    reader.fail("rotation_rpy_rad",
                "expected three finite angles [roll, pitch, yaw] in rad, got " + got);
  };
  if (list.size() != 3) wrong(std::to_string(list.size()) + " entries");
  for (std::size_t i = 0; i < 3; ++i) {
    double v = 0.0;
    try {
      v = list[i].as<double>();
    } catch (const YAML::Exception&) {
      wrong("'" + (list[i].IsScalar() ? list[i].Scalar() : std::string("a non-number")) +
            "' at index " + std::to_string(i));
    }
    if (!std::isfinite(v)) wrong("a non-finite value at index " + std::to_string(i));
    rpy_rad[i] = v;
  }
}

}  // namespace

std::string Ros2Options::odom_topic() const { return ros2_topic(ros_namespace, "odom"); }

std::string Ros2Options::cmd_vel_topic() const { return ros2_topic(ros_namespace, "cmd_vel"); }

std::string Ros2Options::initialpose_topic() const {
  return ros2_topic(ros_namespace, "initialpose");
}

std::string Ros2Options::joint_states_topic() const {
  return ros2_topic(ros_namespace, "joint_states");
}

std::string Ros2Options::tf_topic() { return "rt/tf"; }

std::string Ros2Options::diagnostics_topic() { return "rt/diagnostics"; }

DdsOptions parse_dds_options(const YAML::Node& node, const std::string& file,
                             const std::string& config_dir) {
  ParamReader reader(node, file, "dds");
  DdsOptions options;
  options.domain_id = static_cast<std::uint32_t>(reader.integer_or("domain_id", 0, 0, 232));
  const std::string config = reader.string_or("config", "");
  if (!config.empty()) {
    std::filesystem::path path(config);
    if (path.is_relative()) path = std::filesystem::path(config_dir) / path;
    if (!std::filesystem::is_regular_file(path)) {
      reader.fail("config", "no such Cyclone DDS configuration file '" + path.string() + "'");
    }
    options.config_uri = "file://" + std::filesystem::absolute(path).lexically_normal().string();
  }
  // A DDS Security profile covers domains 0..230 only (the governance's id_range).
  if (options.domain_id > kMaxSecureDomainId && uses_dds_security(options.config_uri)) {
    reader.fail("domain_id", "expected a domain in [0, " + std::to_string(kMaxSecureDomainId) +
                                 "] with DDS Security (" +
                                 resolve_config(options.config_uri).description +
                                 " enables it; a profile's governance covers no more), got " +
                                 std::to_string(options.domain_id));
  }
  options.publish_rate_hz = reader.number_or("publish_rate_hz", 100.0, 1.0, 1000.0);
  options.diagnostics_rate_hz = reader.number_or("diagnostics_rate_hz", 2.0, 0.1, 100.0);
  options.history_depth = reader.integer_or("history_depth", 1, 1, 10);
  const YAML::Node run_samples = reader.raw("run_samples_rate_hz");
  if (run_samples.IsDefined() && run_samples.IsScalar() && run_samples.Scalar() == "off") {
    options.run_samples_rate_hz = 0.0;
  } else {
    options.run_samples_rate_hz = reader.number_or("run_samples_rate_hz", 100.0, 0.0, 1000.0);
  }

  ParamReader ros2 = reader.child("ros2");
  options.ros2.enabled = ros2.boolean_or("enabled", false);
  std::string ros_namespace = ros2.string_or("namespace", "");
  // "/robot1/" and "robot1" name the same namespace.
  while (!ros_namespace.empty() && ros_namespace.front() == '/') ros_namespace.erase(0, 1);
  while (!ros_namespace.empty() && ros_namespace.back() == '/') ros_namespace.pop_back();
  if (!valid_ros_name(ros_namespace)) {
    ros2.fail("namespace", "expected a ROS 2 namespace (letters, digits, '_', '/'), got '" +
                               ros_namespace + "'");
  }
  options.ros2.ros_namespace = ros_namespace;
  options.ros2.node_name = ros2.string_or("node_name", "swiveld");
  if (!valid_ros_name(options.ros2.node_name) ||
      options.ros2.node_name.find('/') != std::string::npos || options.ros2.node_name.empty()) {
    ros2.fail("node_name",
              "expected a ROS 2 node name (letters, digits, '_'; not starting with a digit), "
              "got '" +
                  options.ros2.node_name + "'");
  }
  options.ros2.odom_frame_id = ros2.string_or("odom_frame_id", "odom");
  options.ros2.base_frame_id = ros2.string_or("base_frame_id", "base_link");
  options.ros2.frame_prefix = ros2.string_or("frame_prefix", "");
  // tf2 frame ids carry no leading '/'; the prefix is a ROS name, usually ending in '/'.
  const std::string& prefix = options.ros2.frame_prefix;
  const std::string bare_prefix =
      !prefix.empty() && prefix.back() == '/' ? prefix.substr(0, prefix.size() - 1) : prefix;
  if ((!prefix.empty() && bare_prefix.empty()) || !valid_ros_name(bare_prefix)) {
    ros2.fail("frame_prefix",
              "expected a frame prefix such as 'robot1/' (letters, digits, '_', '/'; no "
              "leading '/'), got '" +
                  prefix + "'");
  }
  options.ros2.publish_tf = ros2.boolean_or("publish_tf", true);
  options.ros2.cmd_vel_stamped = ros2.boolean_or("cmd_vel_stamped", true);
  options.ros2.cmd_vel_max_age_s = ros2.number_or("cmd_vel_max_age_s", 0.5, 0.001, 60.0);
  const auto names = [&](const char* key, std::vector<std::string>& out) {
    const YAML::Node list = ros2.sequence(key);
    for (std::size_t i = 0; i < list.size(); ++i) {
      if (!list[i].IsScalar() || list[i].Scalar().empty()) {
        ros2.fail(key, "expected a list of joint names, got a non-text or empty entry at index " +
                           std::to_string(i));
      }
      out.push_back(list[i].Scalar());
    }
  };
  names("wheel_joints", options.ros2.wheel_joints);
  names("steering_joints", options.ros2.steering_joints);
  for (const char* key : {"imu", "mocap_pose"}) {
    if (ros2.has(key) && !options.ros2.enabled) {
      ros2.fail(key, "a ROS 2 sensor topic needs dds.ros2.enabled: true");
    }
  }
  if (ros2.has("imu")) {
    ParamReader imu = ros2.child("imu");
    parse_sensor_topic(imu, ros_namespace, "imu", options.ros2.imu);
    parse_rotation(imu, options.ros2.imu.rotation_rpy_rad);
    imu.finish();
  }
  if (ros2.has("mocap_pose")) {
    ParamReader pose = ros2.child("mocap_pose");
    parse_sensor_topic(pose, ros_namespace, nullptr, options.ros2.mocap_pose);
    pose.finish();
  }
  if (options.ros2.imu.enabled && options.ros2.mocap_pose.enabled &&
      options.ros2.imu.dds_topic == options.ros2.mocap_pose.dds_topic) {
    ros2.fail("mocap_pose", "topic '" + options.ros2.mocap_pose.dds_topic +
                                "' is the IMU's as well: give each sensor its own topic");
  }
  ros2.finish();
  reader.finish();
  return options;
}

void complete_joints(const RobotModel& robot, const std::string& file, Ros2Options& ros2) {
  const std::size_t modules = robot.module_count();
  const bool steered = robot.drivetrain == DrivetrainKind::kSwpc;
  if (ros2.wheel_joints.empty()) {
    if (steered) {
      for (std::size_t i = 1; i <= modules; ++i) {
        ros2.wheel_joints.push_back("module_" + std::to_string(i) + "_wheel_joint");
      }
    } else {
      ros2.wheel_joints = {"left_wheel_joint", "right_wheel_joint"};
    }
  }
  if (ros2.steering_joints.empty() && steered) {
    for (std::size_t i = 1; i <= modules; ++i) {
      ros2.steering_joints.push_back("module_" + std::to_string(i) + "_steering_joint");
    }
  }
  const std::string robot_text = "robot '" + robot.name + "' (" + robot.source_file + ")";
  if (ros2.wheel_joints.size() != modules) {
    throw ConfigError(file + ": dds.ros2.wheel_joints: expected " + std::to_string(modules) +
                      " names, one per module of " + robot_text + ", got " +
                      std::to_string(ros2.wheel_joints.size()));
  }
  const std::size_t steering = steered ? modules : 0;
  if (ros2.steering_joints.size() != steering) {
    throw ConfigError(file + ": dds.ros2.steering_joints: expected " + std::to_string(steering) +
                      " names" + (steered ? ", one per module of " : " for ") + robot_text +
                      ", got " + std::to_string(ros2.steering_joints.size()));
  }
  ros2.steering_offsets_rad.clear();
  if (steered) {
    for (const SwpcModuleParams& m : robot.modules) {
      ros2.steering_offsets_rad.push_back(m.steering_offset_rad);
    }
  }
}

}  // namespace swivel::dds
