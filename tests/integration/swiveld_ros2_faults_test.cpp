// SPDX-License-Identifier: Apache-2.0
// What a ROS 2 node sees of swiveld around faults, read with the ROS 2 types: rt/odom through
// a stall of the hardware (DDS domain 87) and the diagnostics of a command stream that ends
// with a stop or goes silent inside a motion (DDS domain 88).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "process_util.hpp"
#include "ros2_interfaces.h"
#include "swivel/dds/topics.hpp"

namespace swivel::test {
namespace {

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

std::string daemon_config(int domain, const std::string& ros_namespace, const std::string& hardware,
                          const std::string& command) {
  return "loop: {rate_hz: 500, realtime: false}\n"
         "robot_model: " +
         source_dir() + "/config/robots/docent.yaml\nhardware: " + hardware +
         "\ndrivetrain: {plugin: differential}\nlocalization: {plugin: raw_eg}\ncommand: " +
         command + "\ncontrolled_stop: {linear_deceleration_mps2: 1.0}\ndds:\n  domain_id: " +
         std::to_string(domain) + "\n  config: " + source_dir() +
         "/config/dds/loopback.xml\n  publish_rate_hz: 100\n  diagnostics_rate_hz: 10\n"
         "  ros2: {enabled: true, "
         "namespace: " +
         ros_namespace + ", cmd_vel_stamped: false}\n";
}

struct OdomSample {
  double x_m = 0.0;
  double y_m = 0.0;
  double vx_mps = 0.0;
  std::array<double, 36> pose_covariance{};
  std::array<double, 36> twist_covariance{};
};

double distance_m(const OdomSample& a, const OdomSample& b) {
  return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m);
}

// The twist variance the loop publishes while readings are missing: far above what the
// encoders resolve (~1e-6 m^2/s^2 with the floor).
constexpr double kGapTwistVariance = 1e-4;

// The sim stops answering for 0.5 s at 3 s of sim time while the script drives 0.3 m/s; the
// controlled stop brakes at 1 m/s^2, so the robot travels 0.045 m with no reading.
TEST(SwiveldRos2Faults, OdometryStaysHonestThroughAHardwareStall) {
  constexpr int kDomain = 87;
  const std::string dir = make_test_dir("ros2_gap");
  const std::string config = dir + "/swiveld.yaml";
  std::ofstream(config) << daemon_config(
      kDomain, "it_gap",
      "{plugin: sim, params: {faults: [{kind: stall, start_s: 3.0, duration_s: 0.5}]}}",
      "{source: script, script: [{vx_mps: 0.3, duration_s: 100}]}");
  Child daemon(swiveld_exe(), {"--config", config});

  dds::Participant client({static_cast<std::uint32_t>(kDomain), dds::tool_config_uri()});
  const dds::QosPtr qos = dds::default_qos(1000);
  const dds_entity_t topic =
      dds::create_topic(client.handle(), &nav_msgs_msg_dds__Odometry__desc, "rt/it_gap/odom");
  const dds_entity_t odom = dds_create_reader(client.handle(), topic, qos.get(), nullptr);

  std::vector<OdomSample> samples;
  std::size_t first_gap = 0;
  std::size_t last_gap = 0;
  const auto deadline = std::chrono::steady_clock::now() + Seconds(30);
  while (std::chrono::steady_clock::now() < deadline &&
         (last_gap == 0 || samples.size() < last_gap + 150)) {
    take_all<nav_msgs_msg_dds__Odometry_>(odom, [&](const nav_msgs_msg_dds__Odometry_& m) {
      OdomSample s;
      s.x_m = m.pose.pose.position.x;
      s.y_m = m.pose.pose.position.y;
      s.vx_mps = m.twist.twist.linear.x;
      std::copy(std::begin(m.pose.covariance), std::end(m.pose.covariance),
                s.pose_covariance.begin());
      std::copy(std::begin(m.twist.covariance), std::end(m.twist.covariance),
                s.twist_covariance.begin());
      if (s.twist_covariance[0] > kGapTwistVariance) {
        if (first_gap == 0) first_gap = samples.size();
        last_gap = samples.size();
      }
      samples.push_back(s);
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_GT(first_gap, 0U) << "no stall seen on rt/it_gap/odom\n" << daemon.err();
  ASSERT_GE(samples.size(), last_gap + 150) << daemon.err();
  // 0.5 s at 100 Hz (on a busy machine the publisher may miss some).
  EXPECT_GT(last_gap - first_gap, 30U);

  // Never an exact zero on a diagonal, from the first sample (the start-up pose) on.
  for (std::size_t i = 0; i < samples.size(); ++i) {
    for (std::size_t d = 0; d < 6; ++d) {
      ASSERT_GT(samples[i].pose_covariance[d * 7], 0.0) << "sample " << i << " pose " << d;
      ASSERT_GT(samples[i].twist_covariance[d * 7], 0.0) << "sample " << i << " twist " << d;
    }
  }
  // In the gap: still braking at first, not "v = 0, certain"; the pose's variance grows.
  EXPECT_GT(samples[first_gap].vx_mps, 0.2);
  for (std::size_t i = first_gap + 1; i <= last_gap; ++i) {
    EXPECT_GE(samples[i].pose_covariance[0], samples[i - 1].pose_covariance[0]) << i;
  }
  EXPECT_GT(samples[last_gap].pose_covariance[0], samples[first_gap - 1].pose_covariance[0] + 1e-4);
  EXPECT_NEAR(distance_m(samples[last_gap], samples[first_gap - 1]), 0.045, 0.01);
  // No jump where the readings resume: the robot is at rest by then (0.3 s of braking), and
  // the pose stays where dead reckoning put it (before, it jumped by the 0.045 m travelled).
  EXPECT_LT(distance_m(samples[last_gap + 1], samples[last_gap]), 0.002);
  // Nor anywhere else: no step beyond what a late sample of a robot at 0.3 m/s explains.
  double largest_step_m = 0.0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    largest_step_m = std::max(largest_step_m, distance_m(samples[i], samples[i - 1]));
  }
  EXPECT_LT(largest_step_m, 0.02);
  // At rest after the gap (the fault is latched): zero within the published uncertainty.
  const OdomSample& at_rest = samples.back();
  EXPECT_LE(std::abs(at_rest.vx_mps), 3.0 * std::sqrt(at_rest.twist_covariance[0]));
  EXPECT_GE(at_rest.pose_covariance[0], samples[last_gap].pose_covariance[0]);
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(Seconds(10)), 0) << daemon.err();
  std::filesystem::remove_all(dir);
}

// The statuses of one robot over a while: the worst level for the loop's faults (a warning
// of the DDS side about itself, such as a publish rate missed on a busy machine, aside).
struct DiagnosticsSeen {
  int worst_level = -1;  // over statuses that are not only a DDS warning
  std::string message;
  int samples = 0;
  std::vector<std::string> faults;
  int fault_level = -1;  // over statuses that name a fault (a DDS warning may come with it)
};

TEST(SwiveldRos2Faults, DiagnosticsWarnOnlyForAStreamThatStopsInsideAMotion) {
  constexpr int kDomain = 88;
  const std::string dir = make_test_dir("ros2_idle");
  const std::string config = dir + "/swiveld.yaml";
  std::ofstream(config) << daemon_config(kDomain, "it_idle", "{plugin: sim}",
                                         "{timeout_s: 0.5, source: none}");
  Child daemon(swiveld_exe(), {"--config", config});

  dds::Participant client({static_cast<std::uint32_t>(kDomain), dds::tool_config_uri()});
  const dds::QosPtr qos = dds::default_qos(100);
  const dds_entity_t twist_topic =
      dds::create_topic(client.handle(), &geometry_msgs_msg_dds__Twist__desc, "rt/it_idle/cmd_vel");
  const dds_entity_t cmd_vel = dds_create_writer(client.handle(), twist_topic, qos.get(), nullptr);
  const dds_entity_t diagnostics_topic = dds::create_topic(
      client.handle(), &diagnostic_msgs_msg_dds__DiagnosticArray__desc, "rt/diagnostics");
  const dds_entity_t diagnostics =
      dds_create_reader(client.handle(), diagnostics_topic, qos.get(), nullptr);

  // Nav2's controller: a stream of commands, ending with a zero twist at the goal.
  const auto send_for = [&](double vx_mps, Seconds duration) {
    const auto end = std::chrono::steady_clock::now() + duration;
    while (std::chrono::steady_clock::now() < end) {
      geometry_msgs_msg_dds__Twist_ twist{};
      twist.linear.x = vx_mps;
      ASSERT_EQ(dds_write(cmd_vel, &twist), DDS_RETCODE_OK);
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  };
  const auto watch = [&](Seconds duration) {
    DiagnosticsSeen seen;
    const auto end = std::chrono::steady_clock::now() + duration;
    while (std::chrono::steady_clock::now() < end) {
      take_all<diagnostic_msgs_msg_dds__DiagnosticArray_>(diagnostics, [&](const auto& m) {
        for (std::uint32_t i = 0; i < m.status._length; ++i) {
          const auto& status = m.status._buffer[i];
          if (std::string(status.hardware_id) != "docent") continue;
          ++seen.samples;
          std::string dds_warnings;
          for (std::uint32_t k = 0; k < status.values._length; ++k) {
            const std::string key = status.values._buffer[k].key;
            const std::string value = status.values._buffer[k].value;
            if (key == "fault") seen.faults.push_back(value);
            if (key == "fault" && value != "none")
              seen.fault_level = std::max<int>(seen.fault_level, status.level);
            if (key == "dds_warnings") dds_warnings = value;
          }
          // A busy machine may miss the publish rate (a DDS warning): not what is tested here.
          if (!dds_warnings.empty() && status.level == 1) continue;
          if (status.level > seen.worst_level) {
            seen.worst_level = status.level;
            seen.message = status.message;
          }
        }
      });
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return seen;
  };
  const auto matched = [&] {
    dds_publication_matched_status_t status{};
    return dds_get_publication_matched_status(cmd_vel, &status) == DDS_RETCODE_OK &&
           status.current_count > 0;
  };
  const auto match_deadline = std::chrono::steady_clock::now() + Seconds(20);
  while (!matched() && std::chrono::steady_clock::now() < match_deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(matched()) << "no cmd_vel reader matched\n" << daemon.err();

  send_for(0.2, Seconds(1.0));
  send_for(0.0, Seconds(0.3));
  (void)watch(Seconds(1.0));  // past the timeout, and what was published before it
  const DiagnosticsSeen idle = watch(Seconds(1.5));
  EXPECT_GE(idle.samples, 5) << daemon.err();
  EXPECT_LE(idle.worst_level, 0) << idle.message;
  for (const std::string& fault : idle.faults) EXPECT_EQ(fault, "none");

  send_for(0.2, Seconds(1.0));  // and then silence inside the motion
  (void)watch(Seconds(1.0));
  const DiagnosticsSeen stopped = watch(Seconds(1.0));
  EXPECT_EQ(stopped.fault_level, 1) << stopped.message;
  EXPECT_NE(std::find(stopped.faults.begin(), stopped.faults.end(), "command_timeout"),
            stopped.faults.end())
      << stopped.message;
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(Seconds(10)), 0) << daemon.err();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace swivel::test
