#include "swivel/dds/options.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>

#include "swivel/config/config_error.hpp"
#include "swivel/dds/topics.hpp"

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

// Sets or clears CYCLONEDDS_URI for one test and puts the old value back.
class ScopedUri {
 public:
  explicit ScopedUri(const char* value) {
    if (const char* old = std::getenv("CYCLONEDDS_URI")) old_ = old;
    if (value != nullptr) {
      ::setenv("CYCLONEDDS_URI", value, 1);
    } else {
      ::unsetenv("CYCLONEDDS_URI");
    }
  }
  ~ScopedUri() {
    if (old_) {
      ::setenv("CYCLONEDDS_URI", old_->c_str(), 1);
    } else {
      ::unsetenv("CYCLONEDDS_URI");
    }
  }
  ScopedUri(const ScopedUri&) = delete;
  ScopedUri& operator=(const ScopedUri&) = delete;

 private:
  std::optional<std::string> old_;
};

// The documented rule: the environment wins over dds.config, so that a service drop-in
// setting CYCLONEDDS_URI (the DDS Security profile) takes effect.
TEST(DdsConfigRule, EnvironmentOverridesTheConfigurationFile) {
  const ScopedUri uri("file:///etc/swivel/security/identities/swiveld/cyclonedds.xml");
  const ResolvedConfig resolved = resolve_config("file:///etc/swivel/dds/loopback.xml");

  EXPECT_EQ(resolved.uri, "") << "Cyclone must read CYCLONEDDS_URI itself";
  EXPECT_NE(resolved.description.find("security/identities/swiveld"), std::string::npos)
      << resolved.description;
  EXPECT_NE(resolved.description.find("overrides dds.config file:///etc/swivel/dds/loopback.xml"),
            std::string::npos)
      << resolved.description;
}

TEST(DdsConfigRule, ConfigurationFileWhenTheEnvironmentIsUnset) {
  const ScopedUri uri(nullptr);
  const ResolvedConfig resolved = resolve_config("file:///etc/swivel/dds/loopback.xml");

  EXPECT_EQ(resolved.uri, "file:///etc/swivel/dds/loopback.xml");
  EXPECT_NE(resolved.description.find("dds.config"), std::string::npos) << resolved.description;
}

TEST(DdsConfigRule, EmptyEnvironmentCountsAsUnset) {
  const ScopedUri uri("");
  EXPECT_EQ(resolve_config("file:///x.xml").uri, "file:///x.xml");
}

TEST(DdsConfigRule, LoopbackWhenNeitherIsGiven) {
  const ScopedUri uri(nullptr);
  const ResolvedConfig resolved = resolve_config();

  EXPECT_EQ(resolved.uri.rfind("file://", 0), 0u) << resolved.uri;
  EXPECT_NE(resolved.uri.find("loopback.xml"), std::string::npos) << resolved.uri;
  EXPECT_EQ(tool_config_uri(), resolved.uri);
}

}  // namespace
}  // namespace swivel::dds
