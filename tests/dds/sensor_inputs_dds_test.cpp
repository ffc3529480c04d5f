// SPDX-License-Identifier: Apache-2.0
// The ROS 2 sensor topics end to end in one process: the test's own participant publishes
// sensor_msgs/Imu and geometry_msgs/PoseStamped the way a ROS 2 driver does (the ROS 2
// types, plain CDR, best-effort or reliable writers), the bridge takes them into a running
// 1 kHz control loop (fake plugins), and the test reads the result back as the published
// RobotState (gyro_wz_radps, mode, fault and its cause) and from the localization. Each test
// uses its own ROS 2 namespace, so tests on the same domain do not see each other's topics.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "dds_test_util.hpp"
#include "fake_plugins.hpp"
#include "ros2_imu_publisher.hpp"
#include "ros2_interfaces.h"
#include "swivel.h"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/sensor_inputs.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::dds {
namespace {

using test::ImuPublisher;
using test::publication_matched;
using test::take_one;
using test::unique_robot_id;
using test::wait_for;
using namespace std::chrono_literals;

// A loaded test machine delays DDS delivery now and then: limits well above the 5 ms
// between samples, so that only a publisher that really stopped makes a source stale.
constexpr double kMaxAgeS = 0.3;

// The daemon's wiring of the bridge into the loop (core/src/daemon/daemon.cpp), on fake
// plugins. The bridge stops before the loop it pushes into.
class LiveDaemon {
 public:
  LiveDaemon(const std::string& robot, const DdsOptions& options) {
    rt::LoopOptions loop_options;
    loop_options.realtime = false;
    loop_options.command_timeout_s = 10.0;  // no command timeout during a test
    // The gyro published here is not the fake robot's motion (it stands still).
    loop_options.odometry_check.enabled = false;
    loop_options.external_sensors = loop_sensor_options(options.ros2);
    loop =
        std::make_unique<rt::ControlLoop>(loop_options, hardware, drivetrain, localization, "fake");
    DdsCallbacks callbacks;
    callbacks.read_state = [this](StateSnapshot& s) {
      s = loop->latest();
      return s.cycle > 0;
    };
    callbacks.on_command = [this](const VelocityCommand& c) { return loop->push_command(c); };
    callbacks.on_gyro = [this](const rt::GyroSample& g) { return loop->push_gyro(g); };
    callbacks.on_pose_motion_capture = [this](const MotionCaptureSample& m) {
      return loop->push_motion_capture(m, rt::MotionCaptureSource::kWatched);
    };
    (void)loop->start();
    bridge = std::make_unique<DdsBridge>(options, robot, std::move(callbacks));
    bridge->start();
  }
  ~LiveDaemon() {
    bridge.reset();
    loop->stop();
  }
  LiveDaemon(const LiveDaemon&) = delete;
  LiveDaemon& operator=(const LiveDaemon&) = delete;
  LiveDaemon(LiveDaemon&&) = delete;
  LiveDaemon& operator=(LiveDaemon&&) = delete;

  swivel::test::FakeHardware hardware;
  swivel::test::FakeDrivetrain drivetrain;
  swivel::test::FakeLocalization localization;
  std::unique_ptr<rt::ControlLoop> loop;
  std::unique_ptr<DdsBridge> bridge;
};

DdsOptions imu_options(const std::string& ns, std::array<double, 3> rpy, double grace_s) {
  DdsOptions options;
  options.ros2.enabled = true;
  options.ros2.ros_namespace = ns;
  options.ros2.wheel_joints = {};  // no joint states needed
  options.ros2.imu.enabled = true;
  options.ros2.imu.topic = "imu";
  options.ros2.imu.dds_topic = "rt/" + ns + "/imu";
  options.ros2.imu.max_age_s = kMaxAgeS;
  options.ros2.imu.startup_grace_s = grace_s;
  options.ros2.imu.rotation_rpy_rad = rpy;
  return options;
}

// The newest RobotState of `robot` read within `timeout` that satisfies `done`.
class StateReader {
 public:
  StateReader(const Participant& client, std::string robot) : robot_(std::move(robot)) {
    const dds_entity_t topic =
        create_topic(client.handle(), &swivel_msg_RobotState_desc, kRobotStateTopic);
    const QosPtr qos = default_qos(10);
    reader_ = dds_create_reader(client.handle(), topic, qos.get(), nullptr);
  }
  struct State {
    double gyro_wz_radps = 0.0;
    int mode = 0;
    std::string fault;
    std::string detail;
  };
  bool wait(const std::function<bool(const State&)>& done, std::chrono::milliseconds timeout,
            State& out) {
    return wait_for(
        [&] {
          bool hit = false;
          while (take_one<swivel_msg_RobotState>(reader_, [&](const swivel_msg_RobotState& s) {
            if (robot_ != s.robot_id) return;
            out = {s.gyro_wz_radps, static_cast<int>(s.mode), s.fault_text, s.fault_detail};
            hit = hit || done(out);
          })) {
          }
          return hit;
        },
        timeout);
  }

 private:
  std::string robot_;
  dds_entity_t reader_ = 0;
};

void check_gyro_follows(bool reliable, std::array<double, 3> rpy, double wx, double wy, double wz,
                        double expected_wz) {
  const std::string ns = unique_robot_id(reliable ? "imu_reliable" : "imu_best_effort");
  const DdsOptions options = imu_options(ns, rpy, 10.0);
  LiveDaemon daemon(ns, options);
  Participant client({0, tool_config_uri()});
  StateReader states(client, ns);
  ImuPublisher imu(client, options.ros2.imu.dds_topic, reliable);
  ASSERT_TRUE(wait_for([&] { return imu.matched(); })) << "the IMU reader did not match";

  StateReader::State got;
  const auto published = [&](double value) {
    return [&states, &got, value] {
      return states.wait([&](const auto& st) { return std::abs(st.gyro_wz_radps - value) < 1e-9; },
                         0ms, got);
    };
  };
  ASSERT_TRUE(imu.stream_until(wx, wy, wz, published(expected_wz)))
      << "the published gyro never became " << expected_wz << " (last " << got.gyro_wz_radps << ")";
  EXPECT_EQ(got.fault, "none");
  // It follows a change, too.
  ASSERT_TRUE(imu.stream_until(-wx, -wy, -wz, published(-expected_wz)))
      << "the published gyro did not follow the sign change (last " << got.gyro_wz_radps << ")";
  const SensorCounters counters = daemon.bridge->counters().sensors;
  EXPECT_GE(counters.imu_received, 2U);  // both values went through the ring
  EXPECT_EQ(counters.imu_rejected, 0U);
  EXPECT_EQ(counters.dropped, 0U);
}

TEST(SensorInputsDds, GyroFollowsABestEffortImuPublisher) {
  check_gyro_follows(false, {0.0, 0.0, 0.0}, 0.02, -0.03, 0.35, 0.35);
}

TEST(SensorInputsDds, RotatedMountingGivesTheBodyYawRateFromAReliablePublisher) {
  // Mounted upside down and turned by 90 degrees about z; pitched a little: the body's yaw
  // rate is the z row of R = Rz(pi/2) Ry(0.2) Rx(pi) applied to the IMU's rate.
  const double pitch = 0.2;
  const double wx = 0.1;
  const double wy = -0.05;
  const double wz = 0.4;
  const double expected = -std::sin(pitch) * wx +
                          std::cos(pitch) * std::sin(std::numbers::pi) * wy +
                          std::cos(pitch) * std::cos(std::numbers::pi) * wz;
  ASSERT_LT(expected, -0.3);  // the sign really flips
  check_gyro_follows(true, {std::numbers::pi, pitch, std::numbers::pi / 2}, wx, wy, wz, expected);
}

// From an IMU sample's dds_write to the loop: at 100 Hz over loopback every sample reaches
// the loop, in the order written (the loop's snapshot shows each sample's distinct rate). The
// time each took is printed as a figure, not bounded: timing targets belong in benchmarks.
TEST(SensorInputsDds, EveryImuSampleReachesTheLoopInOrder) {
  const std::string ns = unique_robot_id("imu_latency");
  const DdsOptions options = imu_options(ns, {0.0, 0.0, 0.0}, 10.0);
  LiveDaemon daemon(ns, options);
  Participant client({0, tool_config_uri()});
  ImuPublisher imu(client, options.ros2.imu.dds_topic, false);
  ASSERT_TRUE(wait_for([&] { return imu.matched(); }));
  ASSERT_TRUE(wait_for([&] {
    imu.write(0.0, 0.0, 0.001);
    std::this_thread::sleep_for(5ms);
    return daemon.loop->latest().gyro_wz_radps == 0.001;
  })) << "the IMU never reached the loop";

  constexpr int kSamples = 200;
  std::vector<double> latency_us;
  int reached = 0;
  int out_of_order = 0;  // the loop showed an older sample after this one was written
  double newest_seen = 0.001;
  for (int i = 1; i <= kSamples; ++i) {
    const double value = 0.001 * i + 0.5;
    const auto sent = std::chrono::steady_clock::now();
    imu.write(0.0, 0.0, value);
    StateSnapshot seen = daemon.loop->latest();
    // A liveness limit only: a sample lost for good fails the count below, not a timing.
    while (seen.gyro_wz_radps != value && std::chrono::steady_clock::now() - sent < 5s) {
      if (seen.gyro_wz_radps > 0.5 && seen.gyro_wz_radps < newest_seen) ++out_of_order;
      std::this_thread::sleep_for(20us);
      seen = daemon.loop->latest();
    }
    if (seen.gyro_wz_radps != value) continue;
    ++reached;
    newest_seen = value;
    latency_us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - sent).count());
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_EQ(reached, kSamples) << "samples lost on the way to the loop";
  EXPECT_EQ(out_of_order, 0) << "the loop went back to an older sample";
  ASSERT_FALSE(latency_us.empty());
  std::sort(latency_us.begin(), latency_us.end());
  const auto at = [&](double q) {
    return latency_us[static_cast<std::size_t>(q * static_cast<double>(latency_us.size() - 1))];
  };
  std::printf(
      "IMU dds_write -> loop cycle using it, %zu samples at 100 Hz: median %.0f us, "
      "p95 %.0f us, max %.0f us (1 kHz loop)\n",
      latency_us.size(), at(0.5), at(0.95), latency_us.back());
}

TEST(SensorInputsDds, PoseStampedMotionCaptureReachesTheLocalization) {
  const std::string ns = unique_robot_id("mocap");
  DdsOptions options;
  options.ros2.enabled = true;
  options.ros2.ros_namespace = ns;
  options.ros2.mocap_pose.enabled = true;
  options.ros2.mocap_pose.topic = "/" + ns + "/vrpn/pose";
  options.ros2.mocap_pose.dds_topic = "rt/" + ns + "/vrpn/pose";
  options.ros2.mocap_pose.max_age_s = kMaxAgeS;
  options.ros2.mocap_pose.startup_grace_s = 10.0;
  LiveDaemon daemon(ns, options);
  Participant client({0, tool_config_uri()});
  const dds_entity_t topic =
      create_topic(client.handle(), &geometry_msgs_msg_dds__PoseStamped__desc,
                   options.ros2.mocap_pose.dds_topic.c_str());
  const QosPtr qos = best_effort_qos(10);
  const dds_entity_t writer = dds_create_writer(client.handle(), topic, qos.get(), nullptr);
  ASSERT_TRUE(wait_for([&] { return publication_matched(writer); }));

  const auto write = [&](double x_m, double qz, double qw) {
    std::string frame = "world";
    geometry_msgs_msg_dds__PoseStamped_ m{};
    m.header.frame_id = frame.data();
    m.pose.position = {x_m, -1.0, 0.2};
    m.pose.orientation = {0.0, 0.0, qz, qw};
    ASSERT_EQ(dds_write(writer, &m), DDS_RETCODE_OK);
  };
  // Not a rotation: rejected and counted, never reaching the loop.
  write(99.0, 0.0, 3.0);
  ASSERT_TRUE(wait_for([&] { return daemon.bridge->counters().sensors.mocap_poses_rejected == 1; }))
      << "the non-rotation was not counted";
  EXPECT_NE(daemon.localization.last_motion_capture_x_m.load(), 99.0);

  double qx = 0.0;
  double qy = 0.0;
  double qz = 0.0;
  double qw = 0.0;
  yaw_to_quaternion(0.5, qx, qy, qz, qw);
  ASSERT_TRUE(wait_for([&] {
    write(2.75, qz, qw);
    std::this_thread::sleep_for(5ms);
    return daemon.localization.last_motion_capture_x_m.load() == 2.75;
  })) << "no PoseStamped reached the localization";
  EXPECT_GE(daemon.bridge->counters().sensors.mocap_poses_received, 1U);
  EXPECT_EQ(daemon.loop->latest().fault, FaultCode::kNone);
}

TEST(SensorInputsDds, StoppedImuPublisherSafeStopsNamingTheTopic) {
  const std::string ns = unique_robot_id("imu_stops");
  const DdsOptions options = imu_options(ns, {0.0, 0.0, 0.0}, 10.0);
  LiveDaemon daemon(ns, options);
  Participant client({0, tool_config_uri()});
  StateReader states(client, ns);
  ImuPublisher imu(client, options.ros2.imu.dds_topic, false);
  ASSERT_TRUE(wait_for([&] { return imu.matched(); }));
  // The robot drives while the IMU streams.
  const auto drive = [&] {
    VelocityCommand c;
    c.twist = {0.3, 0.0, 0.0};
    c.received_s = daemon.loop->now_s();
    daemon.loop->push_command(c);
  };
  StateReader::State got;
  ASSERT_TRUE(imu.stream_until(
      0.0, 0.0, 0.1,
      [&] {
        drive();
        return states.wait([](const auto& s) { return s.mode == 1 && s.gyro_wz_radps == 0.1; }, 0ms,
                           got);
      }))
      << "not driving with the IMU's gyro: mode " << got.mode << ", fault " << got.fault;

  // The IMU stops; commands keep coming.
  const auto stopped_at = std::chrono::steady_clock::now();
  bool stale = false;
  ASSERT_TRUE(wait_for([&] {
    drive();
    stale = states.wait([](const auto& s) { return s.fault == "sensor_stale"; }, 0ms, got);
    return stale;
  })) << "no stale fault within 10 s of the IMU stopping";
  const double after_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - stopped_at).count();
  EXPECT_GT(after_s, kMaxAgeS - 0.05);
  std::printf("IMU stopped -> sensor_stale seen in RobotState: %.3f s (max_age_s %.1f)\n", after_s,
              kMaxAgeS);
  EXPECT_EQ(got.mode, 3) << "safe stop";
  EXPECT_EQ(got.detail, options.ros2.imu.dds_topic + ": no IMU sample for over 0.3 s");
  EXPECT_EQ(got.gyro_wz_radps, 0.0);  // no gyro while stale
  // The robot is stopped: zero wheel setpoints (no limits configured) despite the commands.
  std::this_thread::sleep_for(50ms);
  drive();
  std::this_thread::sleep_for(20ms);
  EXPECT_EQ(daemon.hardware.last_left_radps.load(), 0.0);
  EXPECT_EQ(daemon.hardware.last_right_radps.load(), 0.0);
  EXPECT_EQ(daemon.loop->latest().mode, LoopMode::kSafeStop);
}

TEST(SensorInputsDds, ImuNeverHeardFaultsAfterTheGracePeriod) {
  const std::string ns = unique_robot_id("imu_silent");
  const DdsOptions options = imu_options(ns, {0.0, 0.0, 0.0}, 0.5);
  const auto started = std::chrono::steady_clock::now();
  LiveDaemon daemon(ns, options);
  Participant client({0, tool_config_uri()});
  StateReader states(client, ns);
  StateReader::State got;
  ASSERT_TRUE(states.wait([](const auto& s) { return s.fault == "sensor_stale"; }, 10s, got))
      << "no stale fault without an IMU";
  EXPECT_GT(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), 0.5);
  EXPECT_EQ(got.mode, 3);
  EXPECT_EQ(got.detail, options.ros2.imu.dds_topic + ": no IMU sample within 0.5 s of start");
}

}  // namespace
}  // namespace swivel::dds
