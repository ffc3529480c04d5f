// SPDX-License-Identifier: Apache-2.0
// swiveld with dds.ros2 enabled, read by subscribers of the ROS 2 types as a ROS 2 node on
// the domain would create them: the odometry, its transform and the joint states come from
// the same loop cycles and carry the same ROS time; the joint names follow the robot model;
// the diagnostics name the robot. DDS domain 81. A ROS 2 IMU driver's sensor_msgs/Imu
// becomes the daemon's gyro, and its silence stops the robot. DDS domain 82.

#include <gtest/gtest.h>
#include <time.h>

#include <cmath>
#include <set>
#include <string>

#include "process_util.hpp"
#include "ros2_interfaces.h"
#include "swivel.h"
#include "swivel/dds/topics.hpp"

namespace swivel::test {
namespace {

constexpr int kDomain = 81;

std::int64_t stamp_ns(const builtin_interfaces_msg_dds__Time_& t) {
  return static_cast<std::int64_t>(t.sec) * 1'000'000'000 + t.nanosec;
}

// Takes every sample available from `reader`, calling `fn` on the valid ones.
template <typename T, typename Fn>
void take_all(dds_entity_t reader, Fn&& fn) {
  for (;;) {
    void* samples[1] = {nullptr};
    dds_sample_info_t info{};
    if (dds_take(reader, samples, &info, 1, 1) <= 0) return;
    if (info.valid_data) fn(*static_cast<const T*>(samples[0]));
    dds_return_loan(reader, samples, 1);
  }
}

TEST(SwiveldRos2, OdometryTransformJointStatesAndDiagnosticsFromOneDaemon) {
  const std::string dir = make_test_dir("ros2");
  const std::string config = dir + "/swiveld.yaml";
  std::ofstream(config)
      << "loop: {rate_hz: 500, realtime: false}\n"
      << "robot_model: " << source_dir() << "/config/robots/docent.yaml\n"
      << "hardware: {plugin: sim}\n"
      << "drivetrain: {plugin: differential}\n"
      << "localization: {plugin: raw_eg}\n"
      << "command:\n  source: script\n  script:\n"
      << "    - {vx_mps: 0.3, wz_radps: 0.2, duration_s: 100}\n"
      << "dds:\n  domain_id: " << kDomain << "\n  config: " << source_dir()
      << "/config/dds/loopback.xml\n  diagnostics_rate_hz: 10\n"
      << "  ros2: {enabled: true, namespace: it_ros2, odom_frame_id: it_ros2/odom,"
      << " base_frame_id: it_ros2/base_link}\n";
  Child daemon(swiveld_exe(), {"--config", config});

  dds::Participant client({static_cast<std::uint32_t>(kDomain), dds::tool_config_uri()});
  const dds::QosPtr qos = dds::default_qos(100);
  const auto reader = [&](const dds_topic_descriptor_t* desc, const char* name) {
    const dds_entity_t topic = dds::create_topic(client.handle(), desc, name);
    return dds_create_reader(client.handle(), topic, qos.get(), nullptr);
  };
  const dds_entity_t odom = reader(&nav_msgs_msg_dds__Odometry__desc, "rt/it_ros2/odom");
  const dds_entity_t tf = reader(&tf2_msgs_msg_dds__TFMessage__desc, "rt/tf");
  const dds_entity_t joints =
      reader(&sensor_msgs_msg_dds__JointState__desc, "rt/it_ros2/joint_states");
  const dds_entity_t diagnostics =
      reader(&diagnostic_msgs_msg_dds__DiagnosticArray__desc, "rt/diagnostics");

  std::set<std::int64_t> odom_stamps;
  std::set<std::int64_t> tf_stamps;
  std::set<std::int64_t> joint_stamps;
  std::vector<std::string> joint_names;
  std::size_t velocities = 0;
  std::string diagnostic_name;
  int diagnostic_level = -1;
  const auto deadline = std::chrono::steady_clock::now() + Seconds(20);
  while (std::chrono::steady_clock::now() < deadline &&
         (odom_stamps.size() < 50 || tf_stamps.size() < 50 || joint_stamps.size() < 50 ||
          diagnostic_name.empty())) {
    take_all<nav_msgs_msg_dds__Odometry_>(
        odom, [&](const auto& m) { odom_stamps.insert(stamp_ns(m.header.stamp)); });
    take_all<tf2_msgs_msg_dds__TFMessage_>(tf, [&](const auto& m) {
      if (m.transforms._length == 1 &&
          std::string(m.transforms._buffer[0].child_frame_id) == "it_ros2/base_link") {
        tf_stamps.insert(stamp_ns(m.transforms._buffer[0].header.stamp));
      }
    });
    take_all<sensor_msgs_msg_dds__JointState_>(joints, [&](const auto& m) {
      joint_stamps.insert(stamp_ns(m.header.stamp));
      joint_names.clear();
      for (std::uint32_t i = 0; i < m.name._length; ++i)
        joint_names.emplace_back(m.name._buffer[i]);
      velocities = m.velocity._length;
    });
    take_all<diagnostic_msgs_msg_dds__DiagnosticArray_>(diagnostics, [&](const auto& m) {
      for (std::uint32_t i = 0; i < m.status._length; ++i) {
        if (std::string(m.status._buffer[i].hardware_id) != "docent") continue;
        diagnostic_name = m.status._buffer[i].name;
        diagnostic_level = m.status._buffer[i].level;
      }
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_GE(odom_stamps.size(), 50U) << daemon.err();
  ASSERT_GE(tf_stamps.size(), 50U) << daemon.err();
  ASSERT_GE(joint_stamps.size(), 50U) << daemon.err();
  EXPECT_EQ(joint_names, (std::vector<std::string>{"left_wheel_joint", "right_wheel_joint"}));
  EXPECT_EQ(velocities, 2U);
  EXPECT_EQ(diagnostic_name, "swiveld: docent");
  EXPECT_EQ(diagnostic_level, 0);
  // The transform and the joint states of a cycle carry its odometry's stamp: most stamps
  // are common to all three (a reader may miss a sample at the edges of the window).
  std::size_t common = 0;
  for (const std::int64_t s : tf_stamps) {
    if (odom_stamps.contains(s) && joint_stamps.contains(s)) ++common;
  }
  EXPECT_GE(common, tf_stamps.size() - 10);
  // ROS time: within a second of this host's realtime clock.
  timespec real{};
  clock_gettime(CLOCK_REALTIME, &real);
  const double now_s = static_cast<double>(real.tv_sec) + 1e-9 * static_cast<double>(real.tv_nsec);
  EXPECT_NEAR(1e-9 * static_cast<double>(*odom_stamps.rbegin()), now_s, 1.0);
  std::filesystem::remove_all(dir);
}

TEST(SwiveldRos2, GyroFromARos2ImuAndItsSilenceStopsTheRobot) {
  constexpr int kImuDomain = 82;
  const std::string dir = make_test_dir("ros2_imu");
  const std::string config = dir + "/swiveld.yaml";
  // Mounted upside down: the body's yaw rate is minus the IMU's z rate. The robot stands
  // still, so the gyro (0.1 rad/s) stays within the odometry check's margin.
  std::ofstream(config)
      << "loop: {rate_hz: 500, realtime: false}\n"
      << "robot_model: " << source_dir() << "/config/robots/docent.yaml\n"
      << "hardware: {plugin: sim}\n"
      << "drivetrain: {plugin: differential}\n"
      << "localization: {plugin: raw_eg}\n"
      << "command: {source: none}\n"
      << "dds:\n  domain_id: " << kImuDomain << "\n  config: " << source_dir()
      << "/config/dds/loopback.xml\n"
      << "  ros2:\n    enabled: true\n    namespace: it_imu\n"
      << "    imu: {max_age_s: 0.3, startup_grace_s: 20, rotation_rpy_rad: [3.141592653589793, 0, "
         "0]}\n";
  Child daemon(swiveld_exe(), {"--config", config});

  dds::Participant client({static_cast<std::uint32_t>(kImuDomain), dds::tool_config_uri()});
  const dds_entity_t state_topic =
      dds::create_topic(client.handle(), &swivel_msg_RobotState_desc, dds::kRobotStateTopic);
  const dds::QosPtr reliable = dds::default_qos(10);
  const dds_entity_t states =
      dds_create_reader(client.handle(), state_topic, reliable.get(), nullptr);
  const dds_entity_t imu_topic =
      dds::create_topic(client.handle(), &sensor_msgs_msg_dds__Imu__desc, "rt/it_imu/imu");
  const dds::QosPtr sensor_data = dds::best_effort_qos(5);  // a driver's sensor-data QoS
  const dds_entity_t imu =
      dds_create_writer(client.handle(), imu_topic, sensor_data.get(), nullptr);

  double gyro_wz_radps = 0.0;
  std::string fault;
  std::string detail;
  int mode = -1;
  const auto take_states = [&] {
    take_all<swivel_msg_RobotState>(states, [&](const swivel_msg_RobotState& m) {
      if (std::string(m.robot_id) != "docent") return;
      gyro_wz_radps = m.gyro_wz_radps;
      fault = m.fault_text;
      detail = m.fault_detail;
      mode = static_cast<int>(m.mode);
    });
  };
  auto deadline = std::chrono::steady_clock::now() + Seconds(20);
  while (std::chrono::steady_clock::now() < deadline && std::abs(gyro_wz_radps - 0.1) > 1e-9) {
    std::string frame = "imu_link";
    sensor_msgs_msg_dds__Imu_ m{};
    m.header.frame_id = frame.data();
    m.orientation.w = 1.0;
    m.angular_velocity = {0.0, 0.0, -0.1};
    ASSERT_EQ(dds_write(imu, &m), DDS_RETCODE_OK);
    take_states();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_NEAR(gyro_wz_radps, 0.1, 1e-9) << "the published gyro never followed the IMU\n"
                                        << daemon.err();
  EXPECT_EQ(fault, "none") << detail;
  EXPECT_NE(daemon.err().find("gyro from rt/it_imu/imu (sensor_msgs/Imu"), std::string::npos)
      << daemon.err();
  // The diagnostics count the IMU's samples.
  const dds_entity_t diagnostics_topic = dds::create_topic(
      client.handle(), &diagnostic_msgs_msg_dds__DiagnosticArray__desc, "rt/diagnostics");
  const dds_entity_t diagnostics =
      dds_create_reader(client.handle(), diagnostics_topic, reliable.get(), nullptr);
  long imu_samples = -1;
  deadline = std::chrono::steady_clock::now() + Seconds(10);
  while (std::chrono::steady_clock::now() < deadline && imu_samples <= 0) {
    std::string frame = "imu_link";
    sensor_msgs_msg_dds__Imu_ m{};
    m.header.frame_id = frame.data();
    m.orientation.w = 1.0;
    m.angular_velocity = {0.0, 0.0, -0.1};
    ASSERT_EQ(dds_write(imu, &m), DDS_RETCODE_OK);
    take_all<diagnostic_msgs_msg_dds__DiagnosticArray_>(diagnostics, [&](const auto& d) {
      for (std::uint32_t i = 0; i < d.status._length; ++i) {
        const auto& status = d.status._buffer[i];
        if (std::string(status.hardware_id) != "docent") continue;
        for (std::uint32_t k = 0; k < status.values._length; ++k) {
          if (std::string(status.values._buffer[k].key) == "imu_samples") {
            imu_samples = std::stol(status.values._buffer[k].value);
          }
        }
      }
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_GT(imu_samples, 0) << "no imu_samples in the ROS 2 diagnostics";

  // The driver stops publishing: the robot safe-stops, the cause names the topic.
  deadline = std::chrono::steady_clock::now() + Seconds(10);
  while (std::chrono::steady_clock::now() < deadline && fault != "sensor_stale") {
    take_states();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(fault, "sensor_stale") << daemon.err();
  EXPECT_EQ(mode, 3) << "safe stop";
  EXPECT_EQ(detail, "rt/it_imu/imu: no IMU sample for over 0.3 s");
  EXPECT_NE(daemon.err().find("fault sensor_stale (#1): safe stop (rt/it_imu/imu: no IMU sample "
                              "for over 0.3 s)"),
            std::string::npos)
      << daemon.err();
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(Seconds(10)), 0) << daemon.err();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace swivel::test
