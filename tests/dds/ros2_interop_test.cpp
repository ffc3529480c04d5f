// SPDX-License-Identifier: Apache-2.0
// What a ROS 2 user (Nav2, a multi-robot launch, ROS 2's graph tools) meets, checked with
// clients typed from the ROS 2 message definitions as rmw_cyclonedds creates them: a cmd_vel
// publisher of the other type named in the log and the diagnostics; frame_prefix on the
// odometry, /tf and initialpose; the node announced on ros_discovery_info with the GIDs of
// its endpoints and the participant's enclave; a publish rate short of the configured one
// reported.

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "dds_test_util.hpp"
#include "rmw_dds_common.h"
#include "ros2_interfaces.h"
#include "swivel.h"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/options.hpp"
#include "swivel/dds/ros2_node.hpp"
#include "swivel/dds/topics.hpp"

namespace swivel::dds {
namespace {

using test::publication_matched;
using test::subscription_matched;
using test::take_one;
using test::unique_robot_id;
using test::wait_for;

DdsOptions ros2_options(const std::string& ros_namespace) {
  DdsOptions options;
  options.ros2.enabled = true;
  options.ros2.ros_namespace = ros_namespace;
  options.diagnostics_rate_hz = 20.0;
  return options;
}

// The daemon's log while alive (the bridge logs through spdlog's default logger).
class LogCapture {
 public:
  LogCapture()
      : previous_(spdlog::default_logger()),
        sink_(std::make_shared<spdlog::sinks::ostream_sink_mt>(text_)) {
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("swiveld", sink_));
  }
  ~LogCapture() { spdlog::set_default_logger(previous_); }
  LogCapture(const LogCapture&) = delete;
  LogCapture& operator=(const LogCapture&) = delete;
  LogCapture(LogCapture&&) = delete;
  LogCapture& operator=(LogCapture&&) = delete;

  /// How many lines hold `needle`.
  std::size_t count(const std::string& needle) {
    sink_->flush();
    const std::scoped_lock lock(mutex_);
    std::istringstream in(text_.str());
    std::size_t n = 0;
    for (std::string line; std::getline(in, line);) {
      if (line.find(needle) != std::string::npos) ++n;
    }
    return n;
  }

 private:
  std::mutex mutex_;
  std::ostringstream text_;
  std::shared_ptr<spdlog::logger> previous_;
  std::shared_ptr<spdlog::sinks::ostream_sink_mt> sink_;
};

DiagnosticsSample healthy() {
  DiagnosticsSample d;
  d.mode = LoopMode::kVelocity;
  return d;
}

// The newest swivel_diagnostics of `robot` (what `swivelctl status` reads).
struct SwivelDiagnostics {
  bool received = false;
  std::string dds_warnings;
  double publish_rate_hz = 0.0;
  double achieved_publish_rate_hz = 0.0;
};

SwivelDiagnostics take_swivel_diagnostics(dds_entity_t reader, const std::string& robot) {
  SwivelDiagnostics out;
  while (take_one<swivel_msg_Diagnostics>(reader, [&](const swivel_msg_Diagnostics& d) {
    if (robot != d.robot_id) return;
    out.received = true;
    out.dds_warnings = d.dds_warnings;
    out.publish_rate_hz = d.publish_rate_hz;
    out.achieved_publish_rate_hz = d.achieved_publish_rate_hz;
  })) {
  }
  return out;
}

// The newest ROS 2 DiagnosticStatus of `robot` on rt/diagnostics: level and values.
struct RosStatus {
  int level = -1;
  std::string message;
  std::map<std::string, std::string> values;
};

RosStatus take_ros_status(dds_entity_t reader, const std::string& robot) {
  RosStatus out;
  while (take_one<diagnostic_msgs_msg_dds__DiagnosticArray_>(reader, [&](const auto& array) {
    for (std::uint32_t i = 0; i < array.status._length; ++i) {
      const auto& s = array.status._buffer[i];
      if (std::string(s.name) != "swiveld: " + robot) continue;
      out.level = s.level;
      out.message = s.message;
      out.values.clear();
      for (std::uint32_t k = 0; k < s.values._length; ++k) {
        out.values[s.values._buffer[k].key] = s.values._buffer[k].value;
      }
    }
  })) {
  }
  return out;
}

dds_entity_t make_writer(const Participant& client, const dds_topic_descriptor_t* desc,
                         const std::string& topic) {
  const dds_entity_t t = create_topic(client.handle(), desc, topic.c_str());
  const QosPtr qos = default_qos(10);  // Nav2's controller_server and teleop: reliable
  return dds_create_writer(client.handle(), t, qos.get(), nullptr);
}

dds_entity_t make_reader(const Participant& client, const dds_topic_descriptor_t* desc,
                         const std::string& topic) {
  const dds_entity_t t = create_topic(client.handle(), desc, topic.c_str());
  const QosPtr qos = default_qos(10);
  return dds_create_reader(client.handle(), t, qos.get(), nullptr);
}

// Nav2 from Kilted on (and Lyrical) publishes TwistStamped; the daemon configured for Twist
// hears nothing from it, and says so.
TEST(Ros2Interop, TwistStampedPublisherOnATwistCmdVelIsNamed) {
  LogCapture log;
  const std::string ns = unique_robot_id("nav2_stamped");
  DdsOptions options = ros2_options(ns);
  options.ros2.cmd_vel_stamped = false;
  std::atomic<int> commands{0};
  DdsBridge bridge(options, ns,
                   {.read_state = [](StateSnapshot&) { return false; },
                    .on_command =
                        [&](const VelocityCommand&) {
                          ++commands;
                          return true;
                        },
                    .read_diagnostics = healthy});
  Participant client({0, tool_config_uri()});
  const dds_entity_t diagnostics =
      make_reader(client, &swivel_msg_Diagnostics_desc, kDiagnosticsTopic);
  const dds_entity_t ros_diagnostics =
      make_reader(client, &diagnostic_msgs_msg_dds__DiagnosticArray__desc, "rt/diagnostics");
  bridge.start();
  const dds_entity_t nav2 =
      make_writer(client, &geometry_msgs_msg_dds__TwistStamped__desc, "rt/" + ns + "/cmd_vel");
  ASSERT_GT(nav2, 0);

  const std::string expected =
      "a TwistStamped publisher on /" + ns + "/cmd_vel; set dds.ros2.cmd_vel_stamped: true";
  ASSERT_TRUE(wait_for([&] { return bridge.dds_warnings() == expected; }))
      << "got '" << bridge.dds_warnings() << "'";
  SwivelDiagnostics d;
  ASSERT_TRUE(wait_for([&] {
    d = take_swivel_diagnostics(diagnostics, ns);
    return d.dds_warnings == expected;
  })) << "swivel_diagnostics carries '"
      << d.dds_warnings << "'";
  RosStatus status;
  ASSERT_TRUE(wait_for([&] {
    status = take_ros_status(ros_diagnostics, ns);
    return status.values["dds_warnings"] == expected;
  }));
  EXPECT_EQ(status.level, 1);  // WARN
  EXPECT_EQ(status.message, "running; " + expected);
  EXPECT_EQ(status.values["cmd_vel_type"], "geometry_msgs/msg/Twist");

  // Its commands do not match the reader: nothing reaches the loop.
  geometry_msgs_msg_dds__TwistStamped_ m{};
  m.header.frame_id =
      const_cast<char*>("base_link");  // NOLINT(cppcoreguidelines-pro-type-const-cast)
  m.twist.linear.x = 0.2;
  ASSERT_EQ(dds_write(nav2, &m), DDS_RETCODE_OK);

  // A second one is counted, not logged again.
  const dds_entity_t second =
      make_writer(client, &geometry_msgs_msg_dds__TwistStamped__desc, "rt/" + ns + "/cmd_vel");
  ASSERT_TRUE(wait_for([&] {
    return bridge.dds_warnings() ==
           "2 TwistStamped publishers on /" + ns + "/cmd_vel; set dds.ros2.cmd_vel_stamped: true";
  })) << "got '"
      << bridge.dds_warnings() << "'";
  EXPECT_EQ(log.count("a TwistStamped publisher on /" + ns + "/cmd_vel"), 1U);
  EXPECT_EQ(commands.load(), 0);

  // Gone: nothing to say any more.
  ASSERT_EQ(dds_delete(nav2), DDS_RETCODE_OK);
  ASSERT_EQ(dds_delete(second), DDS_RETCODE_OK);
  ASSERT_TRUE(wait_for([&] { return bridge.dds_warnings().empty(); }))
      << "got '" << bridge.dds_warnings() << "'";
  ASSERT_TRUE(wait_for([&] {
    status = take_ros_status(ros_diagnostics, ns);
    return status.level == 0;
  }));
  EXPECT_EQ(status.message, "running");
}

// The default: TwistStamped, as Nav2 sends on the current LTS (Lyrical) and on Kilted; Nav2
// on Jazzy (enable_stamped_cmd_vel false) and teleop_twist_keyboard without stamped:=true
// send Twist.
TEST(Ros2Interop, TwistPublisherOnTheDefaultStampedCmdVelIsNamed) {
  LogCapture log;
  const std::string ns = unique_robot_id("nav2_jazzy");
  const DdsOptions options = ros2_options(ns);
  ASSERT_TRUE(options.ros2.cmd_vel_stamped);
  DdsBridge bridge(
      options, ns,
      {.read_state = [](StateSnapshot&) { return false; }, .read_diagnostics = healthy});
  Participant client({0, tool_config_uri()});
  bridge.start();
  const dds_entity_t teleop =
      make_writer(client, &geometry_msgs_msg_dds__Twist__desc, "rt/" + ns + "/cmd_vel");
  ASSERT_GT(teleop, 0);
  const std::string expected =
      "a Twist publisher on /" + ns + "/cmd_vel; set dds.ros2.cmd_vel_stamped: false";
  ASSERT_TRUE(wait_for([&] { return bridge.dds_warnings() == expected; }))
      << "got '" << bridge.dds_warnings() << "'";
  ASSERT_TRUE(wait_for([&] { return log.count("a Twist publisher on /" + ns) == 1; }));
  // A publisher of the daemon's own type is no finding.
  const dds_entity_t nav2 =
      make_writer(client, &geometry_msgs_msg_dds__TwistStamped__desc, "rt/" + ns + "/cmd_vel");
  ASSERT_TRUE(wait_for([&] { return publication_matched(nav2); }));
  EXPECT_EQ(bridge.dds_warnings(), expected);
}

TEST(Ros2Interop, FramePrefixIsOnTheOdometryTheTransformAndTheInitialPoseCheck) {
  const std::string ns = unique_robot_id("prefixed");
  DdsOptions options = ros2_options(ns);
  options.ros2.frame_prefix = ns + "/";
  std::atomic<std::uint64_t> cycle{0};
  std::mutex mutex;
  std::vector<SetPoseSample> poses;
  DdsBridge bridge(options, ns,
                   {.read_state =
                        [&](StateSnapshot& s) {
                          s = StateSnapshot{};
                          s.cycle = ++cycle;
                          s.stamp_s = swivel::monotonic_s();
                          return true;
                        },
                    .on_set_pose =
                        [&](const SetPoseSample& p) {
                          const std::scoped_lock lock(mutex);
                          poses.push_back(p);
                        }});
  Participant client({0, tool_config_uri()});
  const dds_entity_t odom =
      make_reader(client, &nav_msgs_msg_dds__Odometry__desc, "rt/" + ns + "/odom");
  const dds_entity_t tf = make_reader(client, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf");
  bridge.start();

  std::string odom_frame;
  std::string odom_child;
  ASSERT_TRUE(wait_for([&] {
    return take_one<nav_msgs_msg_dds__Odometry_>(odom, [&](const auto& o) {
      odom_frame = o.header.frame_id;
      odom_child = o.child_frame_id;
    });
  }));
  EXPECT_EQ(odom_frame, ns + "/odom");
  EXPECT_EQ(odom_child, ns + "/base_link");
  std::string tf_parent;
  ASSERT_TRUE(wait_for([&] {
    bool ours = false;
    while (take_one<tf2_msgs_msg_dds__TFMessage_>(tf, [&](const auto& m) {
      if (m.transforms._length != 1) return;
      const auto& t = m.transforms._buffer[0];
      if (std::string(t.child_frame_id) != ns + "/base_link") return;
      ours = true;
      tf_parent = t.header.frame_id;
    })) {
    }
    return ours;
  })) << "no transform to "
      << ns << "/base_link on rt/tf";
  EXPECT_EQ(tf_parent, ns + "/odom");

  // RViz in the robot's namespace sets its pose in the prefixed frame; the bare "odom" is
  // another robot's frame.
  const dds_entity_t initialpose = make_writer(
      client, &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, "rt/" + ns + "/initialpose");
  ASSERT_TRUE(wait_for([&] { return publication_matched(initialpose); }));
  std::string bare = "odom";
  std::string prefixed = ns + "/odom";
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ pose{};
  pose.pose.pose.orientation.w = 1.0;
  pose.header.frame_id = bare.data();
  pose.pose.pose.position.x = 9.0;
  ASSERT_EQ(dds_write(initialpose, &pose), DDS_RETCODE_OK);
  pose.header.frame_id = prefixed.data();
  pose.pose.pose.position.x = 1.5;
  ASSERT_EQ(dds_write(initialpose, &pose), DDS_RETCODE_OK);
  ASSERT_TRUE(wait_for([&] {
    const std::scoped_lock lock(mutex);
    return !poses.empty();
  }));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const std::scoped_lock lock(mutex);
  ASSERT_EQ(poses.size(), 1U) << "the pose in the unprefixed 'odom' was not ignored";
  EXPECT_DOUBLE_EQ(poses[0].pose.pose.x_m, 1.5);
}

bool same_guid(const rmw_dds_common_msg_dds__Gid_& gid, const dds_guid_t& guid) {
  return std::equal(std::begin(gid.data), std::end(gid.data), std::begin(guid.v));
}

bool contains(const dds_sequence_rmw_dds_common_msg_dds__Gid_& gids, const dds_guid_t& guid) {
  return std::any_of(gids._buffer, gids._buffer + gids._length,
                     [&](const auto& gid) { return same_guid(gid, guid); });
}

// What `ros2 node list` and `ros2 topic info -v` read: the participant's enclave in its
// USER_DATA and, on ros_discovery_info, the node with the GIDs of its readers and writers.
// The client joins after the announcement: transient-local durability still delivers it.
TEST(Ros2Interop, AnnouncesTheNodeOnRosDiscoveryInfo) {
  const std::string ns = unique_robot_id("graph");
  DdsOptions options = ros2_options(ns);
  options.ros2.node_name = "swiveld_under_test";
  DdsBridge bridge(options, ns, {.read_state = [](StateSnapshot&) { return false; }});
  bridge.start();
  dds_guid_t participant_guid{};
  ASSERT_EQ(dds_get_guid(bridge.participant(), &participant_guid), DDS_RETCODE_OK);

  Participant client({0, tool_config_uri()});
  // rmw_cyclonedds' graph reader: reliable, transient local, keep last 1 (here a little
  // deeper: other tests' daemons announce on the same domain).
  const dds_entity_t topic =
      create_topic(client.handle(), &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc,
                   kRosDiscoveryInfoTopic);
  const QosPtr qos = default_qos(100);
  dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  const dds_entity_t graph = dds_create_reader(client.handle(), topic, qos.get(), nullptr);
  ASSERT_GT(graph, 0);
  // Endpoints of the node as a ROS 2 peer sees them: their GUIDs come with the match.
  const dds_entity_t odom =
      make_reader(client, &nav_msgs_msg_dds__Odometry__desc, "rt/" + ns + "/odom");
  const dds_entity_t cmd_vel =
      make_writer(client, &geometry_msgs_msg_dds__TwistStamped__desc, "rt/" + ns + "/cmd_vel");
  ASSERT_TRUE(wait_for([&] { return subscription_matched(odom) && publication_matched(cmd_vel); }));
  dds_instance_handle_t handle = 0;
  ASSERT_EQ(dds_get_matched_publications(odom, &handle, 1), 1);
  dds_builtintopic_endpoint_t* odom_writer = dds_get_matched_publication_data(odom, handle);
  ASSERT_NE(odom_writer, nullptr);
  ASSERT_EQ(dds_get_matched_subscriptions(cmd_vel, &handle, 1), 1);
  dds_builtintopic_endpoint_t* cmd_vel_reader = dds_get_matched_subscription_data(cmd_vel, handle);
  ASSERT_NE(cmd_vel_reader, nullptr);

  std::string node_namespace;
  std::string node_name;
  bool odom_listed = false;
  bool cmd_vel_listed = false;
  std::uint32_t nodes = 0;
  ASSERT_TRUE(wait_for([&] {
    bool ours = false;
    while (take_one<rmw_dds_common_msg_dds__ParticipantEntitiesInfo_>(graph, [&](const auto& info) {
      if (!same_guid(info.gid, participant_guid)) return;
      ours = true;
      nodes = info.node_entities_info_seq._length;
      if (nodes != 1) return;
      const auto& node = info.node_entities_info_seq._buffer[0];
      node_namespace = node.node_namespace;
      node_name = node.node_name;
      odom_listed = contains(node.writer_gid_seq, odom_writer->key);
      cmd_vel_listed = contains(node.reader_gid_seq, cmd_vel_reader->key);
    })) {
    }
    return ours;
  })) << "no ParticipantEntitiesInfo of the daemon's participant on ros_discovery_info";
  EXPECT_EQ(nodes, 1U);
  EXPECT_EQ(node_namespace, "/" + ns);
  EXPECT_EQ(node_name, "swiveld_under_test");
  EXPECT_TRUE(odom_listed) << "the odometry writer's GID is not among the node's writers";
  EXPECT_TRUE(cmd_vel_listed) << "the cmd_vel reader's GID is not among the node's readers";
  dds_builtintopic_free_endpoint(odom_writer);
  dds_builtintopic_free_endpoint(cmd_vel_reader);

  // The announcement's writer as a ROS 2 graph cache matches it.
  ASSERT_EQ(dds_get_matched_publications(graph, &handle, 1) >= 1, true);
  bool typed = false;
  dds_instance_handle_t publications[64];
  const dds_return_t n = dds_get_matched_publications(graph, publications, 64);
  for (dds_return_t i = 0; i < n; ++i) {
    dds_builtintopic_endpoint_t* w = dds_get_matched_publication_data(graph, publications[i]);
    if (w == nullptr) continue;
    if (std::memcmp(&w->participant_key, &participant_guid, sizeof participant_guid) == 0) {
      typed = true;
      EXPECT_STREQ(w->type_name, "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_");
      dds_durability_kind_t durability{};
      ASSERT_TRUE(dds_qget_durability(w->qos, &durability));
      EXPECT_EQ(durability, DDS_DURABILITY_TRANSIENT_LOCAL);
      dds_reliability_kind_t reliability{};
      ASSERT_TRUE(dds_qget_reliability(w->qos, &reliability, nullptr));
      EXPECT_EQ(reliability, DDS_RELIABILITY_RELIABLE);
    }
    dds_builtintopic_free_endpoint(w);
  }
  EXPECT_TRUE(typed) << "the daemon's ros_discovery_info writer did not match";

  // USER_DATA "enclave=/;", where rmw_cyclonedds reads a participant's enclave.
  const dds_entity_t participants =
      dds_create_reader(client.handle(), DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr);
  std::string user_data;
  ASSERT_TRUE(wait_for([&] {
    bool found = false;
    while (take_one<dds_builtintopic_participant_t>(participants, [&](const auto& p) {
      if (std::memcmp(&p.key, &participant_guid, sizeof participant_guid) != 0) return;
      void* value = nullptr;
      std::size_t size = 0;
      if (dds_qget_userdata(p.qos, &value, &size)) {
        user_data.assign(static_cast<const char*>(value), size);
        dds_free(value);
      }
      found = true;
    })) {
    }
    return found;
  }));
  EXPECT_EQ(user_data, "enclave=/;");
}

// A loop at 1 kHz and dds.publish_rate_hz 1000, but a snapshot read that takes 4 ms: the
// publisher reaches about 250 states a second and says so.
TEST(Ros2Interop, PublishRateShortOfTheConfiguredOneIsReported) {
  LogCapture log;
  const std::string robot = unique_robot_id("slow_publisher");
  DdsOptions options;
  options.publish_rate_hz = 1000.0;
  options.diagnostics_rate_hz = 10.0;
  const double start_s = swivel::monotonic_s();
  DdsBridge bridge(options, robot,
                   {.read_state =
                        [&](StateSnapshot& s) {
                          std::this_thread::sleep_for(std::chrono::milliseconds(4));
                          const double now_s = swivel::monotonic_s();
                          s = StateSnapshot{};
                          s.cycle = 1 + static_cast<std::uint64_t>((now_s - start_s) * 1000.0);
                          s.stamp_s = start_s + 0.001 * static_cast<double>(s.cycle - 1);
                          return true;
                        },
                    .read_diagnostics = healthy});
  Participant client({0, tool_config_uri()});
  const dds_entity_t diagnostics =
      make_reader(client, &swivel_msg_Diagnostics_desc, kDiagnosticsTopic);
  bridge.start();

  SwivelDiagnostics d;
  ASSERT_TRUE(wait_for(
      [&] {
        d = take_swivel_diagnostics(diagnostics, robot);
        return d.achieved_publish_rate_hz > 0.0;
      },
      std::chrono::seconds(15)))
      << "no achieved publish rate in swivel_diagnostics within 15 s";
  EXPECT_DOUBLE_EQ(d.publish_rate_hz, 1000.0);
  EXPECT_LT(d.achieved_publish_rate_hz, 300.0);
  EXPECT_GT(d.achieved_publish_rate_hz, 10.0);
  EXPECT_NE(d.dds_warnings.find("states published at "), std::string::npos) << d.dds_warnings;
  EXPECT_NE(d.dds_warnings.find("(dds.publish_rate_hz: 1000)"), std::string::npos)
      << d.dds_warnings;
  EXPECT_EQ(log.count("below dds.publish_rate_hz 1000"), 1U);
  EXPECT_DOUBLE_EQ(bridge.counters().achieved_publish_rate_hz, d.achieved_publish_rate_hz);
}

}  // namespace
}  // namespace swivel::dds
