#include "swivel/dds/options.hpp"

#include <gtest/gtest.h>

#include <string>

#include "swivel/config/config_error.hpp"

namespace swivel::dds {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    parse_dds_options(YAML::Load(yaml), "swiveld.yaml", "/etc/swivel");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(DdsOptions, DefaultsWhenAbsent) {
  const DdsOptions options = parse_dds_options(YAML::Node(), "swiveld.yaml", "/etc/swivel");

  EXPECT_EQ(options.domain_id, 0u);
  EXPECT_EQ(options.config_uri, "");
  EXPECT_DOUBLE_EQ(options.publish_rate_hz, 100.0);
  EXPECT_DOUBLE_EQ(options.diagnostics_rate_hz, 2.0);
  EXPECT_EQ(options.history_depth, 1);
  EXPECT_FALSE(options.ros2.enabled);
}

TEST(DdsOptions, ReadsEveryKey) {
  const std::string source_dir = SWIVEL_TEST_SOURCE_DIR;
  const DdsOptions options = parse_dds_options(
      YAML::Load("{domain_id: 7, config: dds/loopback.xml, publish_rate_hz: 50,"
                 " diagnostics_rate_hz: 1, history_depth: 5,"
                 " ros2: {enabled: true, namespace: /robot1/, odom_frame_id: map,"
                 " base_frame_id: base_footprint}}"),
      "swiveld.yaml", source_dir + "/config");

  EXPECT_EQ(options.domain_id, 7u);
  EXPECT_EQ(options.config_uri, "file://" + source_dir + "/config/dds/loopback.xml");
  EXPECT_DOUBLE_EQ(options.publish_rate_hz, 50.0);
  EXPECT_DOUBLE_EQ(options.diagnostics_rate_hz, 1.0);
  EXPECT_EQ(options.history_depth, 5);
  EXPECT_TRUE(options.ros2.enabled);
  EXPECT_EQ(options.ros2.ros_namespace, "robot1");
  EXPECT_EQ(options.ros2.odom_topic(), "rt/robot1/odom");
  EXPECT_EQ(options.ros2.odom_frame_id, "map");
  EXPECT_EQ(options.ros2.base_frame_id, "base_footprint");
}

TEST(DdsOptions, RejectsOutOfRangeRate) {
  const std::string message = error_of("publish_rate_hz: 0");
  EXPECT_NE(message.find("dds.publish_rate_hz"), std::string::npos) << message;
  EXPECT_NE(message.find("swiveld.yaml:1:"), std::string::npos) << message;
}

TEST(DdsOptions, RejectsUnknownKeys) {
  const std::string message = error_of("ros2: {enabled: true, namspace: x}");
  EXPECT_NE(message.find("namspace"), std::string::npos) << message;
}

TEST(DdsOptions, RejectsAMissingConfigFile) {
  const std::string message = error_of("config: nowhere.xml");
  EXPECT_NE(message.find("dds.config"), std::string::npos) << message;
  EXPECT_NE(message.find("/etc/swivel/nowhere.xml"), std::string::npos) << message;
}

TEST(DdsOptions, RejectsABadRosNamespace) {
  const std::string message = error_of("ros2: {namespace: 'robot 1'}");
  EXPECT_NE(message.find("dds.ros2.namespace"), std::string::npos) << message;
  EXPECT_NE(message.find("'robot 1'"), std::string::npos) << message;
}

}  // namespace
}  // namespace swivel::dds
