// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "swivel/config/config_error.hpp"
#include "swivel/dds/options.hpp"
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

  EXPECT_EQ(options.domain_id, 0U);
  EXPECT_EQ(options.config_uri, "");
  EXPECT_DOUBLE_EQ(options.publish_rate_hz, 100.0);
  EXPECT_DOUBLE_EQ(options.diagnostics_rate_hz, 2.0);
  EXPECT_EQ(options.history_depth, 1);
  EXPECT_DOUBLE_EQ(options.run_samples_rate_hz, 100.0);
  EXPECT_FALSE(options.ros2.enabled);
  EXPECT_TRUE(options.ros2.publish_tf);
  // TwistStamped: what Nav2 sends from Kilted on (the current LTS, Lyrical, included).
  EXPECT_TRUE(options.ros2.cmd_vel_stamped);
  EXPECT_DOUBLE_EQ(options.ros2.cmd_vel_max_age_s, 0.5);
  EXPECT_EQ(options.ros2.node_name, "swiveld");
  EXPECT_EQ(options.ros2.node_namespace(), "/");
  EXPECT_EQ(options.ros2.frame_prefix, "");
  EXPECT_EQ(options.ros2.odom_frame(), "odom");
  EXPECT_EQ(options.ros2.base_frame(), "base_link");
  EXPECT_TRUE(options.ros2.wheel_joints.empty());
  EXPECT_TRUE(options.ros2.steering_joints.empty());
}

TEST(DdsOptions, RunSamplesRateIsANumberOrOff) {
  const auto rate = [](const std::string& yaml) {
    return parse_dds_options(YAML::Load(yaml), "swiveld.yaml", "/etc/swivel").run_samples_rate_hz;
  };
  EXPECT_DOUBLE_EQ(rate("{run_samples_rate_hz: 250}"), 250.0);
  EXPECT_DOUBLE_EQ(rate("{run_samples_rate_hz: 0}"), 0.0);
  EXPECT_DOUBLE_EQ(rate("{run_samples_rate_hz: off}"), 0.0);
  EXPECT_NE(error_of("{run_samples_rate_hz: 1001}").find("dds.run_samples_rate_hz"),
            std::string::npos);
  EXPECT_NE(error_of("{run_samples_rate_hz: -1}").find("dds.run_samples_rate_hz"),
            std::string::npos);
  EXPECT_NE(error_of("{run_samples_rate_hz: sometimes}").find("dds.run_samples_rate_hz"),
            std::string::npos);
}

TEST(DdsOptions, ReadsEveryKey) {
  const std::string source_dir = SWIVEL_TEST_SOURCE_DIR;
  const DdsOptions options = parse_dds_options(
      YAML::Load("{domain_id: 7, config: dds/loopback.xml, publish_rate_hz: 50,"
                 " diagnostics_rate_hz: 1, history_depth: 5,"
                 " ros2: {enabled: true, namespace: /robot1/, odom_frame_id: map,"
                 " base_frame_id: base_footprint, publish_tf: false, cmd_vel_stamped: false,"
                 " cmd_vel_max_age_s: 0.2, wheel_joints: [l, r], node_name: base_driver,"
                 " frame_prefix: robot1/}}"),
      "swiveld.yaml", source_dir + "/config");

  EXPECT_EQ(options.domain_id, 7U);
  EXPECT_EQ(options.config_uri, "file://" + source_dir + "/config/dds/loopback.xml");
  EXPECT_DOUBLE_EQ(options.publish_rate_hz, 50.0);
  EXPECT_DOUBLE_EQ(options.diagnostics_rate_hz, 1.0);
  EXPECT_EQ(options.history_depth, 5);
  EXPECT_TRUE(options.ros2.enabled);
  EXPECT_EQ(options.ros2.ros_namespace, "robot1");
  EXPECT_EQ(options.ros2.odom_topic(), "rt/robot1/odom");
  EXPECT_EQ(options.ros2.odom_frame_id, "map");
  EXPECT_EQ(options.ros2.base_frame_id, "base_footprint");
  EXPECT_FALSE(options.ros2.publish_tf);
  EXPECT_FALSE(options.ros2.cmd_vel_stamped);
  EXPECT_DOUBLE_EQ(options.ros2.cmd_vel_max_age_s, 0.2);
  EXPECT_EQ(options.ros2.node_name, "base_driver");
  EXPECT_EQ(options.ros2.node_namespace(), "/robot1");
  EXPECT_EQ(options.ros2.frame_prefix, "robot1/");
  EXPECT_EQ(options.ros2.odom_frame(), "robot1/map");
  EXPECT_EQ(options.ros2.base_frame(), "robot1/base_footprint");
  EXPECT_EQ(options.ros2.wheel_joints, (std::vector<std::string>{"l", "r"}));
}

TEST(DdsOptions, JointNamesDefaultFromTheRobotModelAndMustMatchIt) {
  RobotModel docent;
  docent.name = "docent";
  docent.source_file = "robots/docent.yaml";
  Ros2Options ros2;
  complete_joints(docent, "swiveld.yaml", ros2);
  EXPECT_EQ(ros2.wheel_joints, (std::vector<std::string>{"left_wheel_joint", "right_wheel_joint"}));
  EXPECT_TRUE(ros2.steering_joints.empty());
  EXPECT_TRUE(ros2.steering_offsets_rad.empty());

  RobotModel swpc;
  swpc.name = "swpc2";
  swpc.source_file = "robots/swpc2.yaml";
  swpc.drivetrain = DrivetrainKind::kSwpc;
  swpc.modules.resize(2);
  swpc.modules[1].steering_offset_rad = 0.02;
  Ros2Options casters;
  complete_joints(swpc, "swiveld.yaml", casters);
  EXPECT_EQ(casters.wheel_joints,
            (std::vector<std::string>{"module_1_wheel_joint", "module_2_wheel_joint"}));
  EXPECT_EQ(casters.steering_joints,
            (std::vector<std::string>{"module_1_steering_joint", "module_2_steering_joint"}));
  EXPECT_EQ(casters.steering_offsets_rad, (std::vector<double>{0.0, 0.02}));

  Ros2Options three;
  three.wheel_joints = {"a", "b", "c"};
  try {
    complete_joints(docent, "swiveld.yaml", three);
    ADD_FAILURE() << "three wheel joints accepted for two wheels";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "swiveld.yaml: dds.ros2.wheel_joints: expected 2 names, one per module of robot "
                 "'docent' (robots/docent.yaml), got 3");
  }
  Ros2Options steered;
  steered.steering_joints = {"s1", "s2"};
  EXPECT_THROW(complete_joints(docent, "swiveld.yaml", steered), ConfigError);
}

TEST(DdsOptions, RejectsAnEmptyJointName) {
  EXPECT_EQ(error_of("ros2: {wheel_joints: [left, '']}"),
            "swiveld.yaml:1:8: dds.ros2.wheel_joints: expected a list of joint names, got a "
            "non-text or empty entry at index 1");
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

TEST(DdsOptions, RejectsABadNodeName) {
  EXPECT_NE(error_of("ros2: {node_name: ''}").find("dds.ros2.node_name"), std::string::npos);
  for (const char* bad : {"'swiveld/left'", "'2nd'", "'my node'"}) {
    const std::string message = error_of(std::string("ros2: {node_name: ") + bad + "}");
    EXPECT_NE(message.find("dds.ros2.node_name"), std::string::npos) << message;
    EXPECT_NE(message.find("expected a ROS 2 node name"), std::string::npos) << message;
  }
}

TEST(DdsOptions, RejectsABadFramePrefix) {
  for (const char* bad : {"/robot1/", "'robot 1/'", "/", "robot1//"}) {
    const std::string message = error_of(std::string("ros2: {frame_prefix: ") + bad + "}");
    EXPECT_NE(message.find("dds.ros2.frame_prefix"), std::string::npos) << bad << ": " << message;
  }
  const auto prefix = [](const char* yaml) {
    return parse_dds_options(YAML::Load(yaml), "swiveld.yaml", "/etc/swivel").ros2.odom_frame();
  };
  EXPECT_EQ(prefix("{ros2: {frame_prefix: fleet/robot1/}}"), "fleet/robot1/odom");
  EXPECT_EQ(prefix("{ros2: {frame_prefix: robot1_}}"), "robot1_odom");  // taken as written
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

  EXPECT_EQ(resolved.uri.rfind("file://", 0), 0U) << resolved.uri;
  EXPECT_NE(resolved.uri.find("loopback.xml"), std::string::npos) << resolved.uri;
  EXPECT_EQ(tool_config_uri(), resolved.uri);
}

}  // namespace
}  // namespace swivel::dds
