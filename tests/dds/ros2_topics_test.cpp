// SPDX-License-Identifier: Apache-2.0
// The ROS 2 topics beyond odometry, each read back by its own subscriber created the way
// rmw_cyclonedds creates one (the ROS 2 type, plain CDR, the QoS the ROS 2 consumer uses):
// rt/tf, rt/<ns>/joint_states, rt/diagnostics and a TwistStamped rt/<ns>/cmd_vel with its
// stale-stamp check. rt/tf and rt/diagnostics are absolute, as in ROS 2, so each test names
// its own frames or robot and ignores samples of other tests on the domain.

#include <gtest/gtest.h>
#include <time.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "dds_test_util.hpp"
#include "ros2_interfaces.h"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/options.hpp"
#include "swivel/dds/topics.hpp"

namespace swivel::dds {
namespace {

using test::publication_matched;
using test::take_one;
using test::unique_robot_id;
using test::wait_for;

constexpr std::int64_t kRosStampNs = 1'700'000'123'456'789'012LL;

std::int64_t realtime_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

DdsOptions ros2_options(const std::string& ros_namespace) {
  DdsOptions options;
  options.ros2.enabled = true;
  options.ros2.ros_namespace = ros_namespace;
  return options;
}

// A snapshot at a fixed pose and stamp; cycles advance so that the bridge publishes each.
StateSnapshot snapshot(std::uint64_t cycle) {
  StateSnapshot s;
  s.cycle = cycle;
  s.stamp_s = swivel::monotonic_s();
  s.ros_stamp_ns = kRosStampNs;
  s.estimate.pose = {1.25, -0.5, 0.6};
  s.module_count = 2;
  s.wheel_angle_rad[0] = 10.0;
  s.wheel_angle_rad[1] = 12.5;
  s.wheel_rate_radps[0] = 3.5;
  s.wheel_rate_radps[1] = 4.5;
  s.steer_angle_rad[0] = 0.2;
  s.steer_angle_rad[1] = -0.3;
  s.steer_rate_radps[0] = 0.05;
  s.steer_rate_radps[1] = -0.07;
  s.has_joint_rates = true;
  return s;
}

dds_entity_t make_reader(const Participant& client, const dds_topic_descriptor_t* desc,
                         const std::string& topic, const dds_qos_t* qos) {
  const dds_entity_t t = create_topic(client.handle(), desc, topic.c_str());
  return dds_create_reader(client.handle(), t, qos, nullptr);
}

std::string type_name_of_match(dds_entity_t reader) {
  dds_instance_handle_t publications[8];
  const dds_return_t n = dds_get_matched_publications(reader, publications, 8);
  if (n < 1) return "";
  dds_builtintopic_endpoint_t* endpoint = dds_get_matched_publication_data(reader, publications[0]);
  if (endpoint == nullptr) return "";
  std::string name = endpoint->type_name;
  dds_builtintopic_free_endpoint(endpoint);
  return name;
}

TEST(Ros2Topics, PublishesOdomToBaseOnRtTfForTf2) {
  const std::string tag = unique_robot_id("tf");
  DdsOptions options = ros2_options(tag);
  options.ros2.odom_frame_id = tag + "/odom";
  options.ros2.base_frame_id = tag + "/base_link";
  std::atomic<std::uint64_t> cycle{0};
  DdsBridge bridge(options, tag, {.read_state = [&](StateSnapshot& s) {
                     s = snapshot(++cycle);
                     return true;
                   }});
  Participant client({0, tool_config_uri()});
  // tf2's TransformListener: reliable, volatile, keep-last 100.
  const QosPtr qos = default_qos(100);
  const dds_entity_t reader =
      make_reader(client, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf", qos.get());
  ASSERT_GT(reader, 0);
  bridge.start();

  std::string parent;
  std::string child;
  double x = 0.0;
  double y = 0.0;
  double qz = 0.0;
  double qw = 0.0;
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  ASSERT_TRUE(wait_for([&] {
    bool ours = false;
    while (take_one<tf2_msgs_msg_dds__TFMessage_>(reader, [&](const auto& m) {
      if (m.transforms._length != 1) return;
      const auto& t = m.transforms._buffer[0];
      if (std::string(t.child_frame_id) != options.ros2.base_frame_id) return;
      ours = true;
      parent = t.header.frame_id;
      child = t.child_frame_id;
      x = t.transform.translation.x;
      y = t.transform.translation.y;
      qz = t.transform.rotation.z;
      qw = t.transform.rotation.w;
      sec = t.header.stamp.sec;
      nanosec = t.header.stamp.nanosec;
    })) {
    }
    return ours;
  })) << "no transform on rt/tf within 10 s";
  EXPECT_EQ(parent, tag + "/odom");
  EXPECT_EQ(child, tag + "/base_link");
  EXPECT_DOUBLE_EQ(x, 1.25);
  EXPECT_DOUBLE_EQ(y, -0.5);
  EXPECT_NEAR(qz, std::sin(0.3), 1e-12);
  EXPECT_NEAR(qw, std::cos(0.3), 1e-12);
  EXPECT_EQ(sec, 1'700'000'123);  // the odometry's ROS time
  EXPECT_EQ(nanosec, 456'789'012U);
  EXPECT_EQ(type_name_of_match(reader), "tf2_msgs::msg::dds_::TFMessage_");
}

TEST(Ros2Topics, PublishTfOffLeavesTheTransformToAnotherNode) {
  const std::string tag = unique_robot_id("tf_off");
  DdsOptions options = ros2_options(tag);
  options.ros2.publish_tf = false;
  std::atomic<std::uint64_t> cycle{0};
  DdsBridge bridge(options, tag, {.read_state = [&](StateSnapshot& s) {
                     s = snapshot(++cycle);
                     return true;
                   }});
  Participant client({0, tool_config_uri()});
  const QosPtr qos = default_qos(10);
  const dds_entity_t odom =
      make_reader(client, &nav_msgs_msg_dds__Odometry__desc, options.ros2.odom_topic(), qos.get());
  bridge.start();
  ASSERT_TRUE(wait_for([&] { return take_one<nav_msgs_msg_dds__Odometry_>(odom, [](auto&) {}); }))
      << "no odometry within 10 s";
  // The bridge's participant is discovered: it offers no rt/tf writer.
  dds_instance_handle_t publications[16];
  const dds_entity_t tf =
      make_reader(client, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf", qos.get());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const dds_return_t n = dds_get_matched_publications(tf, publications, 16);
  for (dds_return_t i = 0; i < n; ++i) {
    dds_builtintopic_endpoint_t* e = dds_get_matched_publication_data(tf, publications[i]);
    ASSERT_NE(e, nullptr);
    dds_builtintopic_endpoint_t* o = nullptr;
    dds_instance_handle_t odom_pubs[1];
    if (dds_get_matched_publications(odom, odom_pubs, 1) == 1) {
      o = dds_get_matched_publication_data(odom, odom_pubs[0]);
    }
    ASSERT_NE(o, nullptr);
    EXPECT_NE(std::memcmp(&e->participant_key, &o->participant_key, sizeof(dds_guid_t)), 0)
        << "the bridge published rt/tf with publish_tf: false";
    dds_builtintopic_free_endpoint(o);
    dds_builtintopic_free_endpoint(e);
  }
}

TEST(Ros2Topics, PublishesJointStatesForRobotStatePublisher) {
  const std::string ns = unique_robot_id("joints");
  DdsOptions options = ros2_options(ns);
  options.ros2.wheel_joints = {"module_1_wheel_joint", "module_2_wheel_joint"};
  options.ros2.steering_joints = {"module_1_steering_joint", "module_2_steering_joint"};
  options.ros2.steering_offsets_rad = {0.01, -0.02};
  std::atomic<std::uint64_t> cycle{0};
  std::atomic<bool> rates{false};
  DdsBridge bridge(options, ns, {.read_state = [&](StateSnapshot& s) {
                     s = snapshot(++cycle);
                     s.has_joint_rates = rates.load();
                     return true;
                   }});
  Participant client({0, tool_config_uri()});
  // robot_state_publisher subscribes with the sensor-data profile: best effort.
  const QosPtr qos = best_effort_qos(10);
  const dds_entity_t reader = make_reader(client, &sensor_msgs_msg_dds__JointState__desc,
                                          "rt/" + ns + "/joint_states", qos.get());
  bridge.start();

  struct Joints {
    std::vector<std::string> name;
    std::vector<double> position, velocity;
    std::int32_t sec = 0;
  };
  const auto next = [&] {
    Joints j;
    EXPECT_TRUE(wait_for([&] {
      return take_one<sensor_msgs_msg_dds__JointState_>(reader, [&](const auto& m) {
        for (std::uint32_t i = 0; i < m.name._length; ++i) j.name.emplace_back(m.name._buffer[i]);
        j.position.assign(m.position._buffer, m.position._buffer + m.position._length);
        j.velocity.assign(m.velocity._buffer, m.velocity._buffer + m.velocity._length);
        j.sec = m.header.stamp.sec;
      });
    })) << "no joint states within 10 s";
    return j;
  };
  // Until the loop has fitted rates, positions only (ROS allows an empty velocity array).
  const Joints first = next();
  ASSERT_EQ(first.name,
            (std::vector<std::string>{"module_1_wheel_joint", "module_2_wheel_joint",
                                      "module_1_steering_joint", "module_2_steering_joint"}));
  EXPECT_EQ(first.position, (std::vector<double>{10.0, 12.5, 0.2 + 0.01, -0.3 - 0.02}));
  EXPECT_TRUE(first.velocity.empty());
  EXPECT_EQ(first.sec, 1'700'000'123);
  rates = true;
  Joints later;
  ASSERT_TRUE(wait_for([&] {
    later = next();
    return !later.velocity.empty();
  }));
  EXPECT_EQ(later.velocity, (std::vector<double>{3.5, 4.5, 0.05, -0.07}));
  EXPECT_EQ(type_name_of_match(reader), "sensor_msgs::msg::dds_::JointState_");
}

TEST(Ros2Topics, PublishesDiagnosticArrayForTheAggregator) {
  const std::string robot = unique_robot_id("diag");
  DdsOptions options = ros2_options(robot);
  options.diagnostics_rate_hz = 20.0;
  std::atomic<bool> faulty{false};
  DdsBridge bridge(options, robot,
                   {.read_state = [](StateSnapshot&) { return false; },
                    .read_diagnostics =
                        [&] {
                          DiagnosticsSample d;
                          d.loop_rate_hz = 1000.0;
                          d.measured_rate_hz = 999.9;
                          d.localization_plugin = "kalman";
                          if (faulty) {
                            d.mode = LoopMode::kSafeStop;
                            d.fault = FaultCode::kHardwareError;
                            d.fault_detail = "sim: hardware not answering";
                          }
                          return d;
                        }});
  Participant client({0, tool_config_uri()});
  const QosPtr qos = default_qos(10);
  const dds_entity_t reader = make_reader(client, &diagnostic_msgs_msg_dds__DiagnosticArray__desc,
                                          "rt/diagnostics", qos.get());
  bridge.start();

  struct Status {
    int level = -1;
    std::string name, message, hardware_id;
    std::map<std::string, std::string> values;
    double stamp_s = 0.0;
  };
  const auto next_ours = [&] {
    Status out;
    EXPECT_TRUE(wait_for([&] {
      bool ours = false;
      while (take_one<diagnostic_msgs_msg_dds__DiagnosticArray_>(reader, [&](const auto& m) {
        for (std::uint32_t i = 0; i < m.status._length; ++i) {
          const auto& st = m.status._buffer[i];
          if (std::string(st.hardware_id) != robot) continue;
          ours = true;
          out.level = st.level;
          out.name = st.name;
          out.message = st.message;
          out.hardware_id = st.hardware_id;
          out.values.clear();
          for (std::uint32_t k = 0; k < st.values._length; ++k) {
            out.values[st.values._buffer[k].key] = st.values._buffer[k].value;
          }
          out.stamp_s = m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec;
        }
      })) {
      }
      return ours;
    })) << "no diagnostics for "
        << robot << " within 10 s";
    return out;
  };
  const Status ok = next_ours();
  EXPECT_EQ(ok.level, 0);  // OK
  EXPECT_EQ(ok.name, "swiveld: " + robot);
  EXPECT_EQ(ok.message, "running");
  EXPECT_EQ(ok.values.at("mode"), "idle");
  EXPECT_EQ(ok.values.at("measured_rate_hz"), "999.9");
  EXPECT_EQ(ok.values.at("localization_plugin"), "kalman");
  EXPECT_NEAR(ok.stamp_s, 1e-9 * static_cast<double>(realtime_now_ns()), 10.0);

  faulty = true;
  Status error;
  ASSERT_TRUE(wait_for([&] {
    error = next_ours();
    return error.level != 0;
  }));
  EXPECT_EQ(error.level, 2);  // ERROR
  EXPECT_EQ(error.message, "safe stop: hardware_error (sim: hardware not answering)");
  EXPECT_EQ(error.values.at("mode"), "safe_stop");
  EXPECT_EQ(error.values.at("fault"), "hardware_error");
}

TEST(Ros2Topics, StampedCmdVelDropsStaleCommands) {
  const std::string ns = unique_robot_id("cmd_stamped");
  DdsOptions options = ros2_options(ns);
  options.ros2.cmd_vel_stamped = true;
  options.ros2.cmd_vel_max_age_s = 0.5;
  std::mutex mutex;
  std::vector<double> received;
  DdsBridge bridge(options, ns,
                   {.read_state = [](StateSnapshot&) { return false; },
                    .on_command =
                        [&](const VelocityCommand& c) {
                          const std::scoped_lock lock(mutex);
                          received.push_back(c.twist.vx_mps);
                          return true;
                        }});
  bridge.start();
  Participant client({0, tool_config_uri()});
  const dds_entity_t topic =
      create_topic(client.handle(), &geometry_msgs_msg_dds__TwistStamped__desc,
                   ("rt/" + ns + "/cmd_vel").c_str());
  const QosPtr qos = default_qos(10);  // teleop_twist_keyboard: reliable
  const dds_entity_t writer = dds_create_writer(client.handle(), topic, qos.get(), nullptr);
  ASSERT_TRUE(wait_for([&] { return publication_matched(writer); }));

  const auto send = [&](double vx, std::int64_t stamp_ns) {
    geometry_msgs_msg_dds__TwistStamped_ m{};
    m.header.stamp.sec = static_cast<std::int32_t>(stamp_ns / 1'000'000'000);
    m.header.stamp.nanosec = static_cast<std::uint32_t>(stamp_ns % 1'000'000'000);
    m.header.frame_id = const_cast<char*>("base_link");
    m.twist.linear.x = vx;
    ASSERT_EQ(dds_write(writer, &m), DDS_RETCODE_OK);
  };
  send(0.1, realtime_now_ns() - 2'000'000'000);  // 2 s old: stale
  send(0.2, realtime_now_ns() + 2'000'000'000);  // 2 s ahead: a clock off, stale too
  send(0.3, realtime_now_ns());                  // fresh
  send(0.4, 0);                                  // no stamp: taken as now
  ASSERT_TRUE(wait_for([&] {
    const std::scoped_lock lock(mutex);
    return received.size() >= 2;
  }));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const std::scoped_lock lock(mutex);
  EXPECT_EQ(received, (std::vector<double>{0.3, 0.4}));
  EXPECT_EQ(bridge.counters().commands_stale, 2U);
  EXPECT_EQ(bridge.counters().commands_received, 2U);
}

TEST(Ros2Topics, TopicNamesOfTheNewTopics) {
  Ros2Options options;
  options.ros_namespace = "fleet/docent";
  EXPECT_EQ(options.joint_states_topic(), "rt/fleet/docent/joint_states");
  EXPECT_EQ(options.tf_topic(), "rt/tf");
  EXPECT_EQ(options.diagnostics_topic(), "rt/diagnostics");
}

}  // namespace
}  // namespace swivel::dds
