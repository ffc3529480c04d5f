// SPDX-License-Identifier: Apache-2.0
// The bridge's lifetime and the writes callers make themselves: the DDS entities created (the
// ROS 2 ones when enabled) and the ROS 2 node announced, the threads started and stopped, the
// counters, and the CalibrationResult and Reply written from any thread. What the threads do
// is in bridge_publisher.cpp (with bridge_ros2_state.cpp and bridge_diagnostics.cpp) and
// bridge_subscriber.cpp.
#include "swivel/dds/bridge.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "bridge_entities.hpp"
#include "ros2_interfaces.h"
#include "swivel.h"
#include "swivel/clock.hpp"
#include "swivel/dds/cmd_vel_type_check.hpp"
#include "swivel/dds/ros2_node.hpp"
#include "swivel/dds/sensor_inputs.hpp"
#include "swivel/dds/topics.hpp"

namespace swivel::dds {

DdsBridge::DdsBridge(DdsOptions options, std::string robot_id, DdsCallbacks callbacks)
    : options_(std::move(options)),
      robot_id_(std::move(robot_id)),
      callbacks_(std::move(callbacks)),
      odom_frame_(options_.ros2.odom_frame()),
      base_frame_(options_.ros2.base_frame()) {
  if (robot_id_.empty()) throw std::invalid_argument("DdsBridge: empty robot id");
  if (!callbacks_.read_state) throw std::invalid_argument("DdsBridge: read_state is required");

  dds_ = std::make_unique<Entities>(options_);
  const dds_entity_t pp = dds_->participant.handle();
  const QosPtr writer_qos = default_qos(options_.history_depth);
  // Readers keep a little more so that a burst of commands is not collapsed.
  const QosPtr reader_qos = default_qos(10);

  auto writer = [&](const dds_topic_descriptor_t* desc, const std::string& name,
                    const dds_qos_t* qos) {
    const dds_entity_t topic = create_topic(pp, desc, name.c_str());
    return check(dds_create_writer(pp, topic, qos, nullptr),
                 ("dds_create_writer(" + name + ")").c_str());
  };
  auto reader = [&](const dds_topic_descriptor_t* desc, const std::string& name,
                    const dds_qos_t* qos) {
    const dds_entity_t topic = create_topic(pp, desc, name.c_str());
    return check(dds_create_reader(pp, topic, qos, nullptr),
                 ("dds_create_reader(" + name + ")").c_str());
  };

  dds_->state_writer = writer(&swivel_msg_RobotState_desc, kRobotStateTopic, writer_qos.get());
  dds_->modules_writer =
      writer(&swivel_msg_ModuleStates_desc, kModuleStatesTopic, writer_qos.get());
  dds_->diagnostics_writer =
      writer(&swivel_msg_Diagnostics_desc, kDiagnosticsTopic, writer_qos.get());
  dds_->calibration_writer =
      writer(&swivel_msg_CalibrationResult_desc, kCalibrationResultTopic, writer_qos.get());
  dds_->reply_writer = writer(&swivel_msg_Reply_desc, kReplyTopic, writer_qos.get());
  dds_->command_reader =
      reader(&swivel_msg_VelocityCommand_desc, kVelocityCommandTopic, reader_qos.get());
  dds_->motion_capture_reader =
      reader(&swivel_msg_MotionCapture_desc, kMotionCaptureTopic, reader_qos.get());
  dds_->request_reader = reader(&swivel_msg_Request_desc, kRequestTopic, reader_qos.get());
  dds_->set_pose_reader = reader(&swivel_msg_SetPose_desc, kSetPoseTopic, reader_qos.get());
  if (options_.ros2.enabled) {
    dds_->odom_writer =
        writer(&nav_msgs_msg_dds__Odometry__desc, options_.ros2.odom_topic(), writer_qos.get());
    // Reliable, volatile, keep-last writers like the others: what tf2's listener,
    // robot_state_publisher and the diagnostic aggregator subscribe with (reliable or best
    // effort) matches them.
    if (options_.ros2.publish_tf) {
      dds_->tf_writer =
          writer(&tf2_msgs_msg_dds__TFMessage__desc, Ros2Options::tf_topic(), writer_qos.get());
    }
    if (!options_.ros2.wheel_joints.empty()) {
      dds_->joint_states_writer = writer(&sensor_msgs_msg_dds__JointState__desc,
                                         options_.ros2.joint_states_topic(), writer_qos.get());
    }
    dds_->ros2_diagnostics_writer = writer(&diagnostic_msgs_msg_dds__DiagnosticArray__desc,
                                           Ros2Options::diagnostics_topic(), writer_qos.get());
    // Best effort so that teleop tools with either reliability match.
    const QosPtr cmd_vel_qos = best_effort_qos(10);
    dds_->cmd_vel_reader =
        reader(options_.ros2.cmd_vel_stamped ? &geometry_msgs_msg_dds__TwistStamped__desc
                                             : &geometry_msgs_msg_dds__Twist__desc,
               options_.ros2.cmd_vel_topic(), cmd_vel_qos.get());
    // Reliable, as RViz and `ros2 topic pub` publish it: a one-off pose must not be lost.
    dds_->initialpose_reader = reader(&geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc,
                                      options_.ros2.initialpose_topic(), reader_qos.get());
    dds_->sensors = std::make_unique<SensorInputs>(
        pp, options_.ros2, SensorCallbacks{callbacks_.on_gyro, callbacks_.on_pose_motion_capture});
    dds_->cmd_vel_check = std::make_unique<CmdVelTypeCheck>(pp, options_.ros2.cmd_vel_topic(),
                                                            options_.ros2.cmd_vel_stamped);
    announce_node();
  }

  dds_->waitset = check(dds_create_waitset(pp), "dds_create_waitset");
  const auto sensors = dds_->sensors ? dds_->sensors->readers() : std::array<dds_entity_t, 2>{};
  for (const dds_entity_t r :
       {dds_->command_reader, dds_->motion_capture_reader, dds_->request_reader,
        dds_->set_pose_reader, dds_->cmd_vel_reader, dds_->initialpose_reader, sensors[0],
        sensors[1], dds_->cmd_vel_check ? dds_->cmd_vel_check->reader() : 0}) {
    if (r == 0) continue;
    const dds_entity_t condition =
        check(dds_create_readcondition(r, DDS_ANY_STATE), "dds_create_readcondition");
    check(dds_waitset_attach(dds_->waitset, condition, r), "dds_waitset_attach");
  }
}

DdsBridge::~DdsBridge() { stop(); }

void DdsBridge::announce_node() {
  const auto sensors = dds_->sensors ? dds_->sensors->readers() : std::array<dds_entity_t, 2>{};
  Ros2NodeEntities node{options_.ros2.node_namespace(),
                        options_.ros2.node_name,
                        {dds_->cmd_vel_reader, dds_->initialpose_reader, sensors[0], sensors[1]},
                        {dds_->odom_writer, dds_->tf_writer, dds_->joint_states_writer,
                         dds_->ros2_diagnostics_writer}};
  try {
    announce_ros2_node(dds_->participant.handle(), node);
  } catch (const DdsError& e) {
    // The topics work without it (DDS Security permissions may not grant the topic): ROS
    // tools then list them under an unknown node.
    spdlog::warn("dds: the ROS 2 node {}{}{} is not announced: {}", node.node_namespace,
                 node.node_namespace == "/" ? "" : "/", node.node_name, e.what());
  }
}

void DdsBridge::start() {
  if (publisher_.joinable() || subscriber_.joinable()) {
    throw std::logic_error("DdsBridge::start called twice");
  }
  publisher_ = std::jthread([this](const std::stop_token& stop) { publish_loop(stop); });
  subscriber_ = std::jthread([this](const std::stop_token& stop) { subscribe_loop(stop); });
}

void DdsBridge::stop() noexcept {
  if (subscriber_.joinable()) {
    subscriber_.request_stop();
    dds_waitset_set_trigger(dds_->waitset, true);
    subscriber_.join();
  }
  if (publisher_.joinable()) {
    publisher_.request_stop();
    dds_->wake.notify_all();
    publisher_.join();
  }
}

dds_entity_t DdsBridge::participant() const { return dds_->participant.handle(); }

BridgeCounters DdsBridge::counters() const {
  BridgeCounters c;
  c.states_published = states_published_.load();
  c.commands_received = commands_received_.load();
  c.commands_dropped = commands_dropped_.load();
  c.commands_ignored = commands_ignored_.load();
  c.commands_stale = commands_stale_.load();
  c.motion_captures_received = motion_captures_received_.load();
  c.requests_received = requests_received_.load();
  c.replies_published = replies_published_.load();
  c.publish_failures = publish_failures_.load();
  c.achieved_publish_rate_hz = achieved_publish_rate_hz_.load();
  if (dds_->sensors) c.sensors = dds_->sensors->counters();
  return c;
}

void DdsBridge::publish_calibration(const CalibrationSample& sample) {
  std::array<swivel_msg_ModuleCalibration, kMaxModules> buffer{};
  const std::size_t count = std::min<std::size_t>(sample.modules.size(), kMaxModules);
  for (std::size_t i = 0; i < count; ++i) {
    const auto& m = sample.modules[i];
    buffer[i] = {m.x_m,       m.y_m,       m.delta_rad,       m.d_m,       m.r_m,
                 m.sigma_x_m, m.sigma_y_m, m.sigma_delta_rad, m.sigma_d_m, m.sigma_r_m};
  }
  swivel_msg_CalibrationResult msg{};
  msg.robot_id = c_str(robot_id_);
  msg.stamp_s = monotonic_s();
  msg.status = c_str(sample.status);
  msg.progress = sample.progress;
  msg.text = c_str(sample.text);
  msg.modules._maximum = kMaxModules;
  msg.modules._length = static_cast<std::uint32_t>(count);
  msg.modules._buffer = buffer.data();
  msg.modules._release = false;
  check(dds_write(dds_->calibration_writer, &msg), "dds_write(calibration result)");
}

void DdsBridge::publish_reply(const ReplySample& reply) {
  swivel_msg_Reply msg{};
  msg.robot_id = c_str(robot_id_);
  msg.request_id = reply.request_id;
  msg.verb = c_str(reply.verb);
  msg.ok = reply.ok;
  msg.text = c_str(reply.text);
  const std::scoped_lock lock(dds_->reply_mutex);
  check(dds_write(dds_->reply_writer, &msg), "dds_write(reply)");
  replies_published_.fetch_add(1, std::memory_order_relaxed);
  dds_->reply_ids.push_back(reply.request_id);
  if (dds_->reply_ids.size() > Entities::kRepliesKept) {
    swivel_msg_Reply oldest{};
    oldest.robot_id = c_str(robot_id_);
    oldest.request_id = dds_->reply_ids.front();
    oldest.verb = c_str("");
    oldest.text = c_str("");
    dds_->reply_ids.pop_front();
    (void)dds_unregister_instance(dds_->reply_writer, &oldest);
  }
}

}  // namespace swivel::dds
