// SPDX-License-Identifier: Apache-2.0
// ROS 2 compatibility checked with raw Cyclone entities of the ROS 2 types, as
// rmw_cyclonedds would create them: the wire type name, plain CDR, topic names and the
// field mapping of nav_msgs/Odometry, geometry_msgs/Twist and
// geometry_msgs/PoseWithCovarianceStamped.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "dds_test_util.hpp"
#include "ros2_interfaces.h"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/options.hpp"
#include "swivel/dds/ros_covariance.hpp"
#include "swivel/dds/topics.hpp"

namespace swivel::dds {
namespace {

using test::publication_matched;
using test::take_one;
using test::unique_robot_id;
using test::wait_for;

DdsOptions ros2_options(const std::string& ros_namespace) {
  DdsOptions options;
  options.ros2.enabled = true;
  options.ros2.ros_namespace = ros_namespace;
  return options;
}

TEST(Ros2Compat, PublishesOdometryAsNavMsgsOnRtNamespaceOdom) {
  const std::string ns = unique_robot_id("swivel_test");
  std::atomic<std::uint64_t> cycle{0};
  DdsBridge bridge(ros2_options(ns), "ros2_robot", {.read_state = [&](StateSnapshot& s) {
                     s = StateSnapshot{};
                     s.cycle = ++cycle;
                     s.stamp_s = swivel::monotonic_s();
                     s.ros_stamp_ns = 1'700'000'000'987'654'321LL;
                     s.estimate.pose = {1.0, 2.0, M_PI / 2};
                     s.estimate.has_covariance = true;
                     s.estimate.covariance = {1, 2, 3, 4, 5, 6, 7, 8, 9};
                     s.odometry_twist = {0.5, 0.1, -0.2};
                     s.has_twist_covariance = true;
                     s.twist_covariance = {11, 12, 13, 14, 15, 16, 17, 18, 19};
                     return true;
                   }});
  Participant client({0, tool_config_uri()});
  const dds_entity_t topic = create_topic(client.handle(), &nav_msgs_msg_dds__Odometry__desc,
                                          ("rt/" + ns + "/odom").c_str());
  const QosPtr qos = default_qos(10);
  const dds_entity_t reader = dds_create_reader(client.handle(), topic, qos.get(), nullptr);
  ASSERT_GT(reader, 0);

  bridge.start();

  nav_msgs_msg_dds__Odometry_ odom{};
  std::string frame;
  std::string child_frame;
  ASSERT_TRUE(wait_for([&] {
    return take_one<nav_msgs_msg_dds__Odometry_>(reader, [&](const nav_msgs_msg_dds__Odometry_& o) {
      odom = o;
      frame = o.header.frame_id;
      child_frame = o.child_frame_id;
    });
  })) << "no odometry on rt/"
      << ns << "/odom within 10 s";
  EXPECT_EQ(frame, "odom");
  EXPECT_EQ(child_frame, "base_link");
  // The snapshot's ROS time, mapped by the loop from its monotonic stamp (rt::ClockOffset).
  EXPECT_EQ(odom.header.stamp.sec, 1'700'000'000);
  EXPECT_EQ(odom.header.stamp.nanosec, 987'654'321U);
  EXPECT_DOUBLE_EQ(odom.pose.pose.position.x, 1.0);
  EXPECT_DOUBLE_EQ(odom.pose.pose.position.y, 2.0);
  EXPECT_DOUBLE_EQ(odom.pose.pose.position.z, 0.0);
  EXPECT_NEAR(odom.pose.pose.orientation.z, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(odom.pose.pose.orientation.w, std::sqrt(0.5), 1e-12);
  // (x, y, yaw) land on rows/columns (0, 1, 5) of the 6x6 covariance.
  EXPECT_DOUBLE_EQ(odom.pose.covariance[0], 1.0);
  EXPECT_DOUBLE_EQ(odom.pose.covariance[1], 2.0);
  EXPECT_DOUBLE_EQ(odom.pose.covariance[5], 3.0);
  EXPECT_DOUBLE_EQ(odom.pose.covariance[6], 4.0);
  EXPECT_DOUBLE_EQ(odom.pose.covariance[30], 7.0);
  EXPECT_DOUBLE_EQ(odom.pose.covariance[35], 9.0);
  // z, roll and pitch are constrained by the plane: a small variance, never an exact zero.
  for (const std::size_t i : {14, 21, 28}) {
    EXPECT_DOUBLE_EQ(odom.pose.covariance[i], kConstrainedVariance) << i;
    EXPECT_DOUBLE_EQ(odom.twist.covariance[i], kConstrainedVariance) << i;
  }
  EXPECT_DOUBLE_EQ(odom.pose.covariance[2], 0.0);
  EXPECT_DOUBLE_EQ(odom.twist.twist.linear.x, 0.5);
  EXPECT_DOUBLE_EQ(odom.twist.twist.linear.y, 0.1);
  EXPECT_DOUBLE_EQ(odom.twist.twist.angular.z, -0.2);
  // (vx, vy, wz) on rows/columns (0, 1, 5) of the twist's 6x6 covariance.
  EXPECT_DOUBLE_EQ(odom.twist.covariance[0], 11.0);
  EXPECT_DOUBLE_EQ(odom.twist.covariance[1], 12.0);
  EXPECT_DOUBLE_EQ(odom.twist.covariance[5], 13.0);
  EXPECT_DOUBLE_EQ(odom.twist.covariance[7], 15.0);
  EXPECT_DOUBLE_EQ(odom.twist.covariance[30], 17.0);
  EXPECT_DOUBLE_EQ(odom.twist.covariance[35], 19.0);

  // What a ROS 2 node discovers: the type name and plain CDR only.
  dds_instance_handle_t publications[4];
  const dds_return_t n = dds_get_matched_publications(reader, publications, 4);
  ASSERT_EQ(n, 1);
  dds_builtintopic_endpoint_t* endpoint = dds_get_matched_publication_data(reader, publications[0]);
  ASSERT_NE(endpoint, nullptr);
  EXPECT_STREQ(endpoint->type_name, "nav_msgs::msg::dds_::Odometry_");
  EXPECT_EQ(std::string(endpoint->topic_name), "rt/" + ns + "/odom");
  uint32_t representations = 0;
  dds_data_representation_id_t* values = nullptr;
  ASSERT_TRUE(dds_qget_data_representation(endpoint->qos, &representations, &values));
  ASSERT_EQ(representations, 1U);
  EXPECT_EQ(values[0], DDS_DATA_REPRESENTATION_XCDR1);
  dds_free(values);
  dds_builtintopic_free_endpoint(endpoint);
}

TEST(Ros2Compat, AcceptsCmdVelTwistFromReliableAndBestEffortPublishers) {
  const std::string ns = unique_robot_id("swivel_test_cmd");
  std::mutex mutex;
  std::vector<VelocityCommand> received;
  DdsOptions options = ros2_options(ns);
  options.ros2.cmd_vel_stamped = false;  // Twist, as Nav2 on Jazzy sends by default
  DdsBridge bridge(options, "ros2_robot",
                   {.read_state = [](StateSnapshot&) { return false; },
                    .on_command =
                        [&](const VelocityCommand& c) {
                          const std::scoped_lock lock(mutex);
                          received.push_back(c);
                          return true;
                        }});
  bridge.start();
  Participant client({0, tool_config_uri()});
  const dds_entity_t topic = create_topic(client.handle(), &geometry_msgs_msg_dds__Twist__desc,
                                          ("rt/" + ns + "/cmd_vel").c_str());
  const QosPtr reliable = default_qos(10);
  const QosPtr best_effort = best_effort_qos(10);
  const dds_entity_t reliable_writer =
      dds_create_writer(client.handle(), topic, reliable.get(), nullptr);
  const dds_entity_t best_effort_writer =
      dds_create_writer(client.handle(), topic, best_effort.get(), nullptr);
  ASSERT_TRUE(wait_for([&] {
    return publication_matched(reliable_writer) && publication_matched(best_effort_writer);
  })) << "the bridge's cmd_vel reader did not match both writers within 10 s";

  geometry_msgs_msg_dds__Twist_ twist{};
  twist.linear.x = 0.3;
  twist.linear.y = -0.1;
  twist.angular.z = 0.7;
  ASSERT_EQ(dds_write(reliable_writer, &twist), DDS_RETCODE_OK);

  ASSERT_TRUE(wait_for([&] {
    const std::scoped_lock lock(mutex);
    return !received.empty();
  })) << "no cmd_vel reached on_command within 10 s";
  const std::scoped_lock lock(mutex);
  EXPECT_DOUBLE_EQ(received[0].twist.vx_mps, 0.3);
  EXPECT_DOUBLE_EQ(received[0].twist.vy_mps, -0.1);
  EXPECT_DOUBLE_EQ(received[0].twist.wz_radps, 0.7);
}

// RViz's "2D Pose Estimate" and `ros2 topic pub /initialpose ...`: a reliable
// PoseWithCovarianceStamped. The pose in the odometry frame becomes a set-pose without a
// reply; one in another frame is ignored.
TEST(Ros2Compat, AcceptsInitialPoseInTheOdometryFrame) {
  const std::string ns = unique_robot_id("swivel_test_initialpose");
  std::mutex mutex;
  std::vector<SetPoseSample> received;
  DdsBridge bridge(ros2_options(ns), "ros2_robot",
                   {.read_state = [](StateSnapshot&) { return false; },
                    .on_set_pose =
                        [&](const SetPoseSample& p) {
                          const std::scoped_lock lock(mutex);
                          received.push_back(p);
                        }});
  bridge.start();
  Participant client({0, tool_config_uri()});
  const dds_entity_t topic =
      create_topic(client.handle(), &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc,
                   ("rt/" + ns + "/initialpose").c_str());
  const QosPtr reliable = default_qos(10);
  const dds_entity_t writer = dds_create_writer(client.handle(), topic, reliable.get(), nullptr);
  ASSERT_TRUE(wait_for([&] { return publication_matched(writer); }))
      << "the bridge's initialpose reader did not match within 10 s";

  std::string map = "map";
  std::string odom = "odom";
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg{};
  msg.header.frame_id = map.data();
  msg.pose.pose.position.x = 9.0;
  msg.pose.pose.orientation.w = 1.0;
  ASSERT_EQ(dds_write(writer, &msg), DDS_RETCODE_OK);  // another frame: ignored

  msg.header.frame_id = odom.data();
  msg.pose.pose.position.x = 1.5;
  msg.pose.pose.position.y = -0.5;
  yaw_to_quaternion(0.8, msg.pose.pose.orientation.x, msg.pose.pose.orientation.y,
                    msg.pose.pose.orientation.z, msg.pose.pose.orientation.w);
  msg.pose.covariance[0] = 0.25;     // x
  msg.pose.covariance[7] = 0.16;     // y
  msg.pose.covariance[35] = 0.0685;  // yaw
  msg.pose.covariance[5] = 0.01;     // x-yaw
  ASSERT_EQ(dds_write(writer, &msg), DDS_RETCODE_OK);

  ASSERT_TRUE(wait_for([&] {
    const std::scoped_lock lock(mutex);
    return !received.empty();
  })) << "no initialpose reached on_set_pose within 10 s";
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const std::scoped_lock lock(mutex);
  ASSERT_EQ(received.size(), 1U) << "the pose in frame 'map' was not ignored";
  const SetPoseSample& p = received[0];
  EXPECT_FALSE(p.wants_reply);
  EXPECT_EQ(p.source, "rt/" + ns + "/initialpose");
  EXPECT_DOUBLE_EQ(p.pose.pose.x_m, 1.5);
  EXPECT_DOUBLE_EQ(p.pose.pose.y_m, -0.5);
  EXPECT_NEAR(p.pose.pose.yaw_rad, 0.8, 1e-12);
  ASSERT_TRUE(p.pose.has_covariance);
  EXPECT_DOUBLE_EQ(p.pose.covariance[0], 0.25);
  EXPECT_DOUBLE_EQ(p.pose.covariance[4], 0.16);
  EXPECT_DOUBLE_EQ(p.pose.covariance[8], 0.0685);
  EXPECT_DOUBLE_EQ(p.pose.covariance[2], 0.01);
}

TEST(Ros2Compat, QuaternionToYawInvertsYawToQuaternion) {
  for (const double yaw : {0.0, 0.5, -2.0, 3.1}) {
    double x = 0.0;
    double y = 0.0;
    double z = 0.0;
    double w = 0.0;
    yaw_to_quaternion(yaw, x, y, z, w);
    EXPECT_NEAR(quaternion_to_yaw(x, y, z, w), yaw, 1e-12);
  }
  EXPECT_TRUE(std::isnan(quaternion_to_yaw(0.0, 0.0, 0.0, 0.0)));  // not a rotation
}

TEST(Ros2Compat, TopicNamesFollowTheNamespace) {
  Ros2Options options;
  EXPECT_EQ(options.odom_topic(), "rt/odom");
  EXPECT_EQ(options.cmd_vel_topic(), "rt/cmd_vel");
  EXPECT_EQ(options.initialpose_topic(), "rt/initialpose");
  options.ros_namespace = "fleet/docent";
  EXPECT_EQ(options.odom_topic(), "rt/fleet/docent/odom");
  EXPECT_EQ(options.cmd_vel_topic(), "rt/fleet/docent/cmd_vel");
  EXPECT_EQ(options.initialpose_topic(), "rt/fleet/docent/initialpose");
}

}  // namespace
}  // namespace swivel::dds
