#include "swivel/dds/options.hpp"

#include <filesystem>

#include "swivel/config/param_reader.hpp"

namespace swivel::dds {

namespace {

std::string ros2_topic(const std::string& ros_namespace, const char* name) {
  return ros_namespace.empty() ? std::string("rt/") + name
                               : "rt/" + ros_namespace + "/" + name;
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

}  // namespace

std::string Ros2Options::odom_topic() const { return ros2_topic(ros_namespace, "odom"); }

std::string Ros2Options::cmd_vel_topic() const { return ros2_topic(ros_namespace, "cmd_vel"); }

std::string Ros2Options::initialpose_topic() const {
  return ros2_topic(ros_namespace, "initialpose");
}

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
  options.publish_rate_hz = reader.number_or("publish_rate_hz", 100.0, 1.0, 1000.0);
  options.diagnostics_rate_hz = reader.number_or("diagnostics_rate_hz", 2.0, 0.1, 100.0);
  options.history_depth = reader.integer_or("history_depth", 1, 1, 10);

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
  options.ros2.odom_frame_id = ros2.string_or("odom_frame_id", "odom");
  options.ros2.base_frame_id = ros2.string_or("base_frame_id", "base_link");
  ros2.finish();
  reader.finish();
  return options;
}

}  // namespace swivel::dds
