// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <time.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dds_test_util.hpp"
#include "ros2_interfaces.h"
#include "swivel.h"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/topics.hpp"

namespace swivel::dds {
namespace {

using test::publication_matched;
using test::subscription_matched;
using test::take_one;
using test::unique_robot_id;
using test::wait_for;

StateSnapshot sample_snapshot() {
  StateSnapshot s;
  s.stamp_s = swivel::monotonic_s();
  s.ros_stamp_ns = 1'700'000'000'250'000'001LL;
  s.estimate.pose = {1.5, -2.0, 0.3};
  for (std::size_t i = 0; i < 9; ++i) s.estimate.covariance[i] = 0.1 * static_cast<double>(i + 1);
  s.estimate.has_covariance = true;
  s.odometry_twist = {0.2, -0.05, 0.1};
  for (std::size_t i = 0; i < 9; ++i) s.twist_covariance[i] = 0.01 * static_cast<double>(i + 1);
  s.has_twist_covariance = true;
  s.command_twist = {0.25, 0.0, 0.12};
  s.gyro_wz_radps = 0.11;
  s.module_count = 2;
  s.modules[0] = {0.0, 0.0, 3.0, 2.9};
  s.modules[1] = {0.0, 0.0, 4.0, 3.9};
  s.mode = LoopMode::kVelocity;
  s.fault = FaultCode::kCommandTimeout;
  std::strncpy(s.fault_detail.data(), "velocity command timed out", s.fault_detail.size() - 1);
  s.fault_count = 3;
  std::strncpy(s.localization_plugin.data(), "kalman", s.localization_plugin.size() - 1);
  s.localization_swaps = 2;
  return s;
}

// A loop stand-in: every read returns the sample snapshot with a new cycle number.
struct FakeLoop {
  std::atomic<std::uint64_t> cycle{0};
  bool read(StateSnapshot& out) {
    out = sample_snapshot();
    out.cycle = ++cycle;
    return true;
  }
};

struct Client {
  Client() : participant({0, tool_config_uri()}) {}

  template <typename T>
  dds_entity_t reader(const dds_topic_descriptor_t* desc, const std::string& name, int depth = 10) {
    const dds_entity_t topic = create_topic(participant.handle(), desc, name.c_str());
    const QosPtr qos = default_qos(depth);
    return check(dds_create_reader(participant.handle(), topic, qos.get(), nullptr), "reader");
  }
  dds_entity_t writer(const dds_topic_descriptor_t* desc, const std::string& name) const {
    const dds_entity_t topic = create_topic(participant.handle(), desc, name.c_str());
    const QosPtr qos = default_qos(10);
    return check(dds_create_writer(participant.handle(), topic, qos.get(), nullptr), "writer");
  }

  Participant participant;
};

TEST(DdsBridge, PublishesTheLoopSnapshotAsRobotStateAndModuleStates) {
  const std::string robot = unique_robot_id("state");
  FakeLoop loop;
  DdsBridge bridge({}, robot, {.read_state = [&](StateSnapshot& s) { return loop.read(s); }});
  Client client;
  const dds_entity_t state_reader =
      client.reader<swivel_msg_RobotState>(&swivel_msg_RobotState_desc, kRobotStateTopic);
  const dds_entity_t modules_reader =
      client.reader<swivel_msg_ModuleStates>(&swivel_msg_ModuleStates_desc, kModuleStatesTopic);

  bridge.start();

  swivel_msg_RobotState got{};
  std::string id;
  std::string plugin;
  std::string fault;
  std::string detail;
  ASSERT_TRUE(wait_for([&] {
    return take_one<swivel_msg_RobotState>(state_reader,
                                           [&](const swivel_msg_RobotState& s) {
                                             got = s;
                                             id = s.robot_id;
                                             plugin = s.localization_plugin;
                                             fault = s.fault_text;
                                             detail = s.fault_detail;
                                           }) &&
           id == robot;
  })) << "no RobotState within 10 s";
  EXPECT_GT(got.cycle, 0U);
  EXPECT_NEAR(got.stamp_s, swivel::monotonic_s(), 5.0);
  EXPECT_EQ(got.ros_stamp_sec, 1'700'000'000);
  EXPECT_EQ(got.ros_stamp_nanosec, 250'000'001U);
  EXPECT_DOUBLE_EQ(got.x_m, 1.5);
  EXPECT_DOUBLE_EQ(got.y_m, -2.0);
  EXPECT_DOUBLE_EQ(got.yaw_rad, 0.3);
  EXPECT_TRUE(got.has_covariance);
  EXPECT_DOUBLE_EQ(got.pose_covariance[0], 0.1);
  EXPECT_DOUBLE_EQ(got.pose_covariance[8], 0.9);
  EXPECT_DOUBLE_EQ(got.vx_mps, 0.2);
  EXPECT_DOUBLE_EQ(got.vy_mps, -0.05);
  EXPECT_DOUBLE_EQ(got.wz_radps, 0.1);
  EXPECT_TRUE(got.has_twist_covariance);
  EXPECT_DOUBLE_EQ(got.twist_covariance[0], 0.01);
  EXPECT_DOUBLE_EQ(got.twist_covariance[8], 0.09);
  EXPECT_DOUBLE_EQ(got.cmd_vx_mps, 0.25);
  EXPECT_DOUBLE_EQ(got.cmd_wz_radps, 0.12);
  EXPECT_DOUBLE_EQ(got.gyro_wz_radps, 0.11);
  EXPECT_EQ(plugin, "kalman");
  EXPECT_EQ(got.localization_swaps, 2U);
  EXPECT_EQ(got.mode, swivel_msg_LOOP_MODE_VELOCITY);
  EXPECT_EQ(got.fault_code, static_cast<std::uint16_t>(FaultCode::kCommandTimeout));
  EXPECT_EQ(fault, "command_timeout");
  EXPECT_EQ(detail, "velocity command timed out");
  EXPECT_EQ(got.fault_count, 3U);
  EXPECT_FALSE(got.has_truth);

  std::vector<swivel_msg_ModuleState> modules;
  std::string modules_id;
  ASSERT_TRUE(wait_for([&] {
    return take_one<swivel_msg_ModuleStates>(
               modules_reader,
               [&](const swivel_msg_ModuleStates& m) {
                 modules_id = m.robot_id;
                 modules.assign(m.modules._buffer, m.modules._buffer + m.modules._length);
               }) &&
           modules_id == robot;
  })) << "no ModuleStates within 10 s";
  ASSERT_EQ(modules.size(), 2U);
  EXPECT_DOUBLE_EQ(modules[0].wheel_rate_cmd_radps, 3.0);
  EXPECT_DOUBLE_EQ(modules[1].wheel_rate_meas_radps, 3.9);
}

TEST(DdsBridge, PublishesNothingNewWhileTheLoopStalls) {
  const std::string robot = unique_robot_id("stall");
  // The loop stopped after cycle 7: every read returns the same snapshot.
  DdsBridge bridge({}, robot, {.read_state = [](StateSnapshot& s) {
                     s = sample_snapshot();
                     s.cycle = 7;
                     return true;
                   }});

  bridge.start();
  ASSERT_TRUE(wait_for([&] { return bridge.counters().states_published > 0; }));
  // 30 publish periods at 100 Hz: a bridge that republished would have written many.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));

  EXPECT_EQ(bridge.counters().states_published, 1U);
}

TEST(DdsBridge, PassesVelocityCommandsForThisRobotOnly) {
  const std::string robot = unique_robot_id("command");
  FakeLoop loop;
  std::mutex mutex;
  std::vector<VelocityCommand> received;
  DdsBridge bridge({}, robot,
                   {.read_state = [&](StateSnapshot& s) { return loop.read(s); },
                    .on_command =
                        [&](const VelocityCommand& c) {
                          const std::scoped_lock lock(mutex);
                          received.push_back(c);
                          return true;
                        }});
  bridge.start();
  Client client;
  const dds_entity_t writer =
      client.writer(&swivel_msg_VelocityCommand_desc, kVelocityCommandTopic);
  ASSERT_TRUE(wait_for([&] { return publication_matched(writer); }));

  std::string other = robot + "_other";
  swivel_msg_VelocityCommand command{};
  command.robot_id = other.data();
  command.vx_mps = 9.0;
  ASSERT_EQ(dds_write(writer, &command), DDS_RETCODE_OK);
  std::string own = robot;
  command.robot_id = own.data();
  command.vx_mps = 0.4;
  command.vy_mps = 0.1;
  command.wz_radps = -0.3;
  ASSERT_EQ(dds_write(writer, &command), DDS_RETCODE_OK);

  ASSERT_TRUE(wait_for([&] {
    const std::scoped_lock lock(mutex);
    return !received.empty();
  })) << "no command reached on_command within 10 s";
  const std::scoped_lock lock(mutex);
  ASSERT_EQ(received.size(), 1U);
  EXPECT_DOUBLE_EQ(received[0].twist.vx_mps, 0.4);
  EXPECT_DOUBLE_EQ(received[0].twist.vy_mps, 0.1);
  EXPECT_DOUBLE_EQ(received[0].twist.wz_radps, -0.3);
  EXPECT_NEAR(received[0].received_s, swivel::monotonic_s(), 5.0);
  EXPECT_EQ(received[0].sequence, 1U);
  EXPECT_EQ(bridge.counters().commands_ignored, 1U);
  EXPECT_EQ(bridge.counters().commands_received, 1U);
}

TEST(DdsBridge, CountsCommandsTheLoopCannotQueueAsDropped) {
  const std::string robot = unique_robot_id("dropped");
  FakeLoop loop;
  DdsBridge bridge({}, robot,
                   {.read_state = [&](StateSnapshot& s) { return loop.read(s); },
                    .on_command = [](const VelocityCommand&) { return false; }});
  bridge.start();
  Client client;
  const dds_entity_t writer =
      client.writer(&swivel_msg_VelocityCommand_desc, kVelocityCommandTopic);
  ASSERT_TRUE(wait_for([&] { return publication_matched(writer); }));

  std::string own = robot;
  swivel_msg_VelocityCommand command{};
  command.robot_id = own.data();
  ASSERT_EQ(dds_write(writer, &command), DDS_RETCODE_OK);

  ASSERT_TRUE(wait_for([&] { return bridge.counters().commands_dropped == 1; }));
  EXPECT_EQ(bridge.counters().commands_received, 0U);
}

TEST(DdsBridge, PassesMotionCaptureAndRequests) {
  const std::string robot = unique_robot_id("mocap");
  FakeLoop loop;
  std::mutex mutex;
  std::vector<MotionCaptureSample> captures;
  std::vector<RequestSample> requests;
  DdsBridge bridge({}, robot,
                   {.read_state = [&](StateSnapshot& s) { return loop.read(s); },
                    .on_motion_capture =
                        [&](const MotionCaptureSample& m) {
                          const std::scoped_lock lock(mutex);
                          captures.push_back(m);
                          return true;
                        },
                    .on_request =
                        [&](const RequestSample& r) {
                          const std::scoped_lock lock(mutex);
                          requests.push_back(r);
                        }});
  bridge.start();
  Client client;
  const dds_entity_t mocap = client.writer(&swivel_msg_MotionCapture_desc, kMotionCaptureTopic);
  const dds_entity_t request = client.writer(&swivel_msg_Request_desc, kRequestTopic);
  ASSERT_TRUE(wait_for([&] { return publication_matched(mocap) && publication_matched(request); }));

  std::string own = robot;
  swivel_msg_MotionCapture m{};
  m.robot_id = own.data();
  m.stamp_s = 12.5;
  m.x_m = 1.0;
  m.y_m = 2.0;
  m.yaw_rad = -0.5;
  ASSERT_EQ(dds_write(mocap, &m), DDS_RETCODE_OK);
  m.stamp_s = 0.0;  // "at reception"
  ASSERT_EQ(dds_write(mocap, &m), DDS_RETCODE_OK);
  std::string verb = "reload";
  std::string argument;
  swivel_msg_Request r{};
  r.robot_id = own.data();
  r.verb = verb.data();
  r.argument = argument.data();
  r.request_id = 5;
  ASSERT_EQ(dds_write(request, &r), DDS_RETCODE_OK);

  ASSERT_TRUE(wait_for([&] {
    const std::scoped_lock lock(mutex);
    return captures.size() == 2 && requests.size() == 1;
  })) << "motion capture or request missing after 10 s";
  const std::scoped_lock lock(mutex);
  EXPECT_TRUE(captures[0].valid);
  EXPECT_DOUBLE_EQ(captures[0].stamp_s, 12.5);
  EXPECT_DOUBLE_EQ(captures[0].pose.x_m, 1.0);
  EXPECT_DOUBLE_EQ(captures[0].pose.y_m, 2.0);
  EXPECT_DOUBLE_EQ(captures[0].pose.yaw_rad, -0.5);
  EXPECT_NEAR(captures[1].stamp_s, swivel::monotonic_s(), 5.0);
  EXPECT_EQ(requests[0].verb, "reload");
  EXPECT_EQ(requests[0].argument, "");
  EXPECT_EQ(requests[0].request_id, 5U);
}

// swivelctl set-pose's SetPose reaches on_set_pose with the sigmas as variances, and the
// Reply the daemon publishes reaches a reader keyed by robot and request id.
TEST(DdsBridge, DeliversSetPoseAndPublishesItsReply) {
  const std::string robot = unique_robot_id("set_pose");
  FakeLoop loop;
  std::mutex mutex;
  std::vector<SetPoseSample> poses;
  DdsBridge bridge({}, robot,
                   {.read_state = [&](StateSnapshot& s) { return loop.read(s); },
                    .on_set_pose =
                        [&](const SetPoseSample& p) {
                          const std::scoped_lock lock(mutex);
                          poses.push_back(p);
                        }});
  bridge.start();
  Client client;
  const dds_entity_t writer = client.writer(&swivel_msg_SetPose_desc, kSetPoseTopic);
  const dds_entity_t replies = client.reader<swivel_msg_Reply>(&swivel_msg_Reply_desc, kReplyTopic);
  ASSERT_TRUE(
      wait_for([&] { return publication_matched(writer) && subscription_matched(replies); }));

  std::string own = robot;
  swivel_msg_SetPose p{};
  p.robot_id = own.data();
  p.request_id = 77;
  p.x_m = 1.0;
  p.y_m = -2.0;
  p.yaw_rad = 0.5;
  p.has_covariance = true;
  p.sigma_x_m = 0.1;
  p.sigma_y_m = -0.2;  // stays visible as a negative variance
  p.sigma_yaw_rad = 0.05;
  ASSERT_EQ(dds_write(writer, &p), DDS_RETCODE_OK);
  ASSERT_TRUE(wait_for([&] {
    const std::scoped_lock lock(mutex);
    return poses.size() == 1;
  })) << "no SetPose reached on_set_pose within 10 s";
  {
    const std::scoped_lock lock(mutex);
    EXPECT_EQ(poses[0].request_id, 77U);
    EXPECT_TRUE(poses[0].wants_reply);
    EXPECT_EQ(poses[0].pose.pose.y_m, -2.0);
    EXPECT_TRUE(poses[0].pose.has_covariance);
    EXPECT_NEAR(poses[0].pose.covariance[0], 0.01, 1e-15);
    EXPECT_NEAR(poses[0].pose.covariance[4], -0.04, 1e-15);
    EXPECT_NEAR(poses[0].pose.covariance[8], 0.0025, 1e-15);
    EXPECT_EQ(poses[0].pose.covariance[1], 0.0);
  }

  bridge.publish_reply({77, "set_pose", false, "refused: negative variance"});
  bool ok = true;
  std::string text;
  std::uint64_t id = 0;
  ASSERT_TRUE(wait_for([&] {
    return take_one<swivel_msg_Reply>(replies, [&](const swivel_msg_Reply& r) {
      ok = r.ok;
      text = r.text;
      id = r.request_id;
    });
  })) << "no Reply within 10 s";
  EXPECT_EQ(id, 77U);
  EXPECT_FALSE(ok);
  EXPECT_EQ(text, "refused: negative variance");
  EXPECT_EQ(bridge.counters().replies_published, 1U);
}

TEST(DdsBridge, PublishesDiagnostics) {
  const std::string robot = unique_robot_id("diagnostics");
  FakeLoop loop;
  DiagnosticsSample d;
  d.loop_rate_hz = 1000.0;
  d.measured_rate_hz = 999.5;
  d.lateness = {12.0, 40.0, 80.0, 150.0};
  d.cycle_time = {5.0, 9.0, 20.0, 31.0};
  d.cycles = 12345;
  d.overruns = 2;
  d.fault = FaultCode::kHardwareError;
  d.fault_detail = "sim: hardware not answering";
  d.localization_plugin = "lsm";
  d.drivetrain_plugin = "differential";
  d.hardware_plugin = "sim";
  d.reload_count = 1;
  d.last_reload_ok = false;
  d.last_reload_result = "swiveld.yaml:3:1: loop: unknown key";
  DdsOptions options;
  options.diagnostics_rate_hz = 20.0;
  DdsBridge bridge(options, robot,
                   {.read_state = [&](StateSnapshot& s) { return loop.read(s); },
                    .read_diagnostics = [&] { return d; }});
  Client client;
  const dds_entity_t reader =
      client.reader<swivel_msg_Diagnostics>(&swivel_msg_Diagnostics_desc, kDiagnosticsTopic);

  bridge.start();

  swivel_msg_Diagnostics got{};
  std::string id;
  std::string plugin;
  std::string reload;
  std::string fault;
  std::string detail;
  ASSERT_TRUE(wait_for([&] {
    return take_one<swivel_msg_Diagnostics>(reader,
                                            [&](const swivel_msg_Diagnostics& m) {
                                              got = m;
                                              id = m.robot_id;
                                              plugin = m.localization_plugin;
                                              reload = m.last_reload_result;
                                              fault = m.fault_text;
                                              detail = m.fault_detail;
                                            }) &&
           id == robot;
  })) << "no Diagnostics within 10 s";
  EXPECT_DOUBLE_EQ(got.loop_rate_hz, 1000.0);
  EXPECT_DOUBLE_EQ(got.lateness.p99_us, 40.0);
  EXPECT_DOUBLE_EQ(got.cycle_time.p999_us, 20.0);
  EXPECT_DOUBLE_EQ(got.cycle_time.max_us, 31.0);
  EXPECT_EQ(got.cycles, 12345U);
  EXPECT_EQ(got.overruns, 2U);
  EXPECT_EQ(fault, "hardware_error");
  EXPECT_EQ(detail, "sim: hardware not answering");
  EXPECT_EQ(plugin, "lsm");
  EXPECT_EQ(got.reload_count, 1U);
  EXPECT_FALSE(got.last_reload_ok);
  EXPECT_EQ(reload, "swiveld.yaml:3:1: loop: unknown key");
}

// A publisher round that fails (here the diagnostics source throws) is counted every time
// and logged at the 1st, 2nd, 4th, ... failure with its message; the publisher goes on.
TEST(DdsBridge, CountsEveryPublishingFailureAndLogsItsMessage) {
  const std::string robot = unique_robot_id("publish_failures");
  FakeLoop loop;
  DdsOptions options;
  options.diagnostics_rate_hz = 100.0;
  std::ostringstream log_text;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log_text);
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("captured", sink));
  {
    DdsBridge bridge(options, robot,
                     {.read_state = [&](StateSnapshot& s) { return loop.read(s); },
                      .read_diagnostics = []() -> DiagnosticsSample {
                        throw std::runtime_error("diagnostics source gone");
                      }});
    bridge.start();
    EXPECT_TRUE(wait_for([&] { return bridge.counters().publish_failures >= 5; }))
        << bridge.counters().publish_failures << " failures counted";
    bridge.stop();
  }
  spdlog::set_default_logger(previous);
  const std::string text = log_text.str();
  EXPECT_NE(text.find("dds: publishing failed (failure 1): diagnostics source gone"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("dds: publishing failed (failure 4): diagnostics source gone"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("(failure 3)"), std::string::npos) << "logged every failure: " << text;
}

TEST(DdsBridge, PublishesCalibrationResults) {
  const std::string robot = unique_robot_id("calibration");
  FakeLoop loop;
  DdsBridge bridge({}, robot, {.read_state = [&](StateSnapshot& s) { return loop.read(s); }});
  Client client;
  const dds_entity_t reader = client.reader<swivel_msg_CalibrationResult>(
      &swivel_msg_CalibrationResult_desc, kCalibrationResultTopic);
  ASSERT_TRUE(wait_for([&] { return subscription_matched(reader); }));

  CalibrationSample sample;
  sample.status = "done";
  sample.progress = 1.0;
  sample.modules.push_back({.x_m = 0.215, .y_m = 0.125, .sigma_x_m = 0.001});
  bridge.publish_calibration(sample);

  std::string status;
  std::vector<swivel_msg_ModuleCalibration> modules;
  ASSERT_TRUE(wait_for([&] {
    return take_one<swivel_msg_CalibrationResult>(
        reader, [&](const swivel_msg_CalibrationResult& c) {
          status = c.status;
          modules.assign(c.modules._buffer, c.modules._buffer + c.modules._length);
        });
  }));
  EXPECT_EQ(status, "done");
  ASSERT_EQ(modules.size(), 1U);
  EXPECT_DOUBLE_EQ(modules[0].x_m, 0.215);
  EXPECT_DOUBLE_EQ(modules[0].sigma_x_m, 0.001);
}

TEST(DdsBridge, RejectsAnEmptyRobotId) {
  EXPECT_THROW(DdsBridge({}, "", {.read_state = [](StateSnapshot&) { return false; }}),
               std::invalid_argument);
}

}  // namespace
}  // namespace swivel::dds
