// SPDX-License-Identifier: Apache-2.0
#include "swivel/dds/bridge.hpp"

#include <spdlog/spdlog.h>
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include "ros2_interfaces.h"
#include "swivel.h"
#include "swivel/clock.hpp"
#include "swivel/dds/cmd_vel_type_check.hpp"
#include "swivel/dds/publish_rate_meter.hpp"
#include "swivel/dds/ros2_node.hpp"
#include "swivel/dds/ros_covariance.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/rt/clock_offset.hpp"
#include "take_all.hpp"

namespace swivel::dds {

namespace {

swivel_msg_LoopMode to_msg(LoopMode mode) {
  switch (mode) {
    case LoopMode::kIdle: return swivel_msg_LOOP_MODE_IDLE;
    case LoopMode::kVelocity: return swivel_msg_LOOP_MODE_VELOCITY;
    case LoopMode::kCalibration: return swivel_msg_LOOP_MODE_CALIBRATION;
    case LoopMode::kSafeStop: return swivel_msg_LOOP_MODE_SAFE_STOP;
  }
  return swivel_msg_LOOP_MODE_SAFE_STOP;
}

swivel_msg_TimingStats to_msg(const TimingPercentiles& p) {
  return {p.p50_us, p.p99_us, p.p999_us, p.max_us};
}

// idlc's C types hold strings as char*, in samples that are only written too: Cyclone reads
// through the pointer and never writes.
// NOLINTBEGIN(cppcoreguidelines-pro-type-const-cast)
char* c_str(const std::string& s) { return const_cast<char*>(s.c_str()); }
char* c_str(const char* s) { return const_cast<char*>(s); }
// NOLINTEND(cppcoreguidelines-pro-type-const-cast)

// CLOCK_REALTIME now, ns: ROS time for what the bridge stamps itself (diagnostics, the
// stale check of stamped commands); loop samples carry the loop's own mapping.
std::int64_t realtime_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// Points an idlc sequence at `length` elements the caller owns (written, never freed).
template <typename Sequence, typename Element>
void borrow(Sequence& sequence, Element* elements, std::uint32_t length) {
  sequence._maximum = length;
  sequence._length = length;
  sequence._buffer = elements;
  sequence._release = false;
}

}  // namespace

void yaw_to_quaternion(double yaw_rad, double& x, double& y, double& z, double& w) noexcept {
  x = 0.0;
  y = 0.0;
  z = std::sin(0.5 * yaw_rad);
  w = std::cos(0.5 * yaw_rad);
}

double quaternion_to_yaw(double x, double y, double z, double w) noexcept {
  const double norm = std::sqrt(x * x + y * y + z * z + w * w);
  if (!std::isfinite(norm) || std::abs(norm - 1.0) > 0.01) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

struct DdsBridge::Entities {
  // CYCLONEDDS_URI, then dds.config, then Swivel's loopback-only file (resolve_config()):
  // never Cyclone's defaults, which would send discovery out of every interface.
  // With ROS 2 on, the participant's USER_DATA names its enclave as rmw_cyclonedds does.
  explicit Entities(const DdsOptions& options)
      : participant({options.domain_id, resolve_config(options.config_uri).uri},
                    options.ros2.enabled ? kRos2ParticipantUserData : "") {}

  Participant participant;
  dds_entity_t state_writer = 0;
  dds_entity_t modules_writer = 0;
  dds_entity_t diagnostics_writer = 0;
  dds_entity_t calibration_writer = 0;
  dds_entity_t reply_writer = 0;
  dds_entity_t odom_writer = 0;              ///< ROS 2, 0 when disabled
  dds_entity_t tf_writer = 0;                ///< ROS 2, 0 when disabled or publish_tf is off
  dds_entity_t joint_states_writer = 0;      ///< ROS 2, 0 when disabled or no joints named
  dds_entity_t ros2_diagnostics_writer = 0;  ///< ROS 2, 0 when disabled
  dds_entity_t command_reader = 0;
  dds_entity_t motion_capture_reader = 0;
  dds_entity_t request_reader = 0;
  dds_entity_t set_pose_reader = 0;
  dds_entity_t cmd_vel_reader = 0;                 ///< ROS 2, 0 when disabled
  dds_entity_t initialpose_reader = 0;             ///< ROS 2, 0 when disabled
  std::unique_ptr<SensorInputs> sensors;           ///< ROS 2 sensor topics, null when disabled
  std::unique_ptr<CmdVelTypeCheck> cmd_vel_check;  ///< ROS 2, null when disabled
  dds_entity_t waitset = 0;

  std::mutex wake_mutex;
  std::condition_variable_any wake;

  // Reply instances still registered, oldest first (publish_reply()).
  static constexpr std::size_t kRepliesKept = 32;
  std::mutex reply_mutex;
  std::deque<std::uint64_t> reply_ids;
};

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

namespace {

using PublishClock = std::chrono::steady_clock;  // CLOCK_MONOTONIC on Linux, like stamp_s

PublishClock::time_point at_monotonic(double stamp_s) {
  return PublishClock::time_point(
      std::chrono::duration_cast<PublishClock::duration>(std::chrono::duration<double>(stamp_s)));
}

// The publisher follows the loop's phase. It sleeps until kEarly before the cycle it is to
// publish begins, then polls the snapshot (yielding between looks, for at most kSpin) and
// sends that cycle's state as soon as the loop has written it: a sample leaves the
// loop's cycle work plus one DDS hop after its stamp, not up to a publish period later.
// Polling costs the publisher about kEarly plus one cycle's work per sample; the loop
// does nothing for it. A cycle that does not come within kSpin (a stalled loop, or one
// slower than the publish rate) is waited for in steps of kRetry; after kMaxWait the newest
// snapshot goes out and the schedule restarts from it.
constexpr auto kEarly = std::chrono::microseconds(150);
constexpr auto kSpin = std::chrono::microseconds(1000);
constexpr auto kRetry = std::chrono::microseconds(100);
constexpr auto kMaxWait = std::chrono::milliseconds(5);

}  // namespace

void DdsBridge::publish_loop(const std::stop_token& stop) {
  // The default 50 us timer slack would be most of the age this schedule saves.
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  const double period_s = 1.0 / options_.publish_rate_hz;
  const auto period =
      std::chrono::duration_cast<PublishClock::duration>(std::chrono::duration<double>(period_s));
  const auto diagnostics_period = std::chrono::duration_cast<PublishClock::duration>(
      std::chrono::duration<double>(1.0 / options_.diagnostics_rate_hz));
  auto next_diagnostics = PublishClock::now();
  std::uint64_t last_cycle = 0;
  bool have_last = false;
  double due_stamp_s = 0.0;           // the next cycle to publish is the first stamped from here
  PublishClock::time_point due_at{};  // when it is due (epoch: any new cycle is)
  StateSnapshot snapshot;
  std::uint64_t newest_cycle = 0;  // the loop's, published or not
  PublishRateMeter rate(options_.publish_rate_hz);

  // A new cycle (true) and whether it is the one due; the loop's wake-up jitter in the
  // stamps is tolerated up to 1 % of the publish period.
  const auto look = [&](bool& due) {
    const bool have = callbacks_.read_state(snapshot);
    if (have) newest_cycle = snapshot.cycle;
    const bool fresh = have && (!have_last || snapshot.cycle != last_cycle);
    due = fresh && snapshot.stamp_s >= due_stamp_s - 0.01 * period_s;
    return fresh;
  };

  std::unique_lock lock(dds_->wake_mutex);
  while (!stop.stop_requested()) {
    auto next = PublishClock::now() + kRetry;
    try {
      bool due = false;
      bool fresh = look(due);
      const auto spin_until = std::min(PublishClock::now(), due_at) + kSpin;
      while (!due && have_last && PublishClock::now() < spin_until && !stop.stop_requested()) {
        std::this_thread::yield();
        fresh = look(due);
      }
      const auto now = PublishClock::now();
      if (due || (fresh && now >= due_at + kMaxWait)) {
        // Publish only new cycles: a stalled loop shows as a gap, not as repeated samples.
        publish_state(snapshot);
        last_cycle = snapshot.cycle;
        have_last = true;
        due_stamp_s = snapshot.stamp_s + period_s;
        due_at = at_monotonic(due_stamp_s);
        next = due_at - kEarly;
        // After a long stall the snapshot is old: restart the schedule from now.
        if (due_at < now) {
          due_at = now + period;
          due_stamp_s = 0.0;
          next = due_at;
        }
      } else if (now >= due_at + kMaxWait) {
        // Nothing new for a while (a stalled or stopped loop): look once a period.
        next = now + period;
      }
      measure_publish_rate(rate, newest_cycle);
      if (callbacks_.read_diagnostics && PublishClock::now() >= next_diagnostics) {
        publish_diagnostics(callbacks_.read_diagnostics());
        next_diagnostics += diagnostics_period;
        if (next_diagnostics < PublishClock::now()) {
          next_diagnostics = PublishClock::now() + diagnostics_period;
        }
      }
    } catch (const std::exception& e) {
      // Every failure is counted (diagnostics publish_failures); the log has the 1st, 2nd,
      // 4th, 8th, ...: a lasting failure stays visible without flooding it.
      const std::uint64_t failures = publish_failures_.fetch_add(1, std::memory_order_relaxed) + 1;
      if (std::has_single_bit(failures)) {
        spdlog::warn("dds: publishing failed (failure {}): {}", failures, e.what());
      }
    }
    if (callbacks_.read_diagnostics && next_diagnostics < next) next = next_diagnostics;
    dds_->wake.wait_until(lock, stop, next, [] { return false; });
  }
}

void DdsBridge::measure_publish_rate(PublishRateMeter& rate, std::uint64_t newest_cycle) {
  const auto change = rate.update(monotonic_s(), states_published_.load(), newest_cycle);
  achieved_publish_rate_hz_.store(rate.achieved_hz());
  attainable_publish_rate_hz_.store(rate.attainable_hz());
  publish_rate_short_.store(rate.short_of_rate());
  if (change == PublishRateMeter::Change::kFellShort) {
    spdlog::warn(
        "dds: published {:.1f} states/s, below dds.publish_rate_hz {:g}{}: subscribers get "
        "fewer samples than configured (diagnostics: achieved_publish_rate_hz)",
        rate.achieved_hz(), options_.publish_rate_hz,
        rate.attainable_hz() < options_.publish_rate_hz
            ? fmt::format(" and the loop's {:.1f} cycles/s", rate.attainable_hz())
            : std::string());
  } else if (change == PublishRateMeter::Change::kRecovered) {
    spdlog::info("dds: publishing at {:.1f} states/s again (dds.publish_rate_hz {:g})",
                 rate.achieved_hz(), options_.publish_rate_hz);
  }
}

std::string DdsBridge::dds_warnings() const {
  std::string text = dds_->cmd_vel_check ? dds_->cmd_vel_check->warning() : std::string();
  if (publish_rate_short_.load()) {
    if (!text.empty()) text += "; ";
    text += fmt::format("states published at {:.1f} Hz of {:.1f} Hz attainable ",
                        achieved_publish_rate_hz_.load(), attainable_publish_rate_hz_.load()) +
            fmt::format("(dds.publish_rate_hz: {:g})", options_.publish_rate_hz);
  }
  return text;
}

void DdsBridge::publish_state(const StateSnapshot& s) {
  std::array<char, sizeof(ShortName) + 1> plugin{};
  std::copy(s.localization_plugin.begin(), s.localization_plugin.end(), plugin.begin());

  swivel_msg_RobotState state{};
  state.robot_id = c_str(robot_id_);
  state.cycle = s.cycle;
  state.stamp_s = s.stamp_s;
  const rt::RosTime ros_stamp = rt::to_ros_time(s.ros_stamp_ns);
  state.ros_stamp_sec = ros_stamp.sec;
  state.ros_stamp_nanosec = ros_stamp.nanosec;
  state.x_m = s.estimate.pose.x_m;
  state.y_m = s.estimate.pose.y_m;
  state.yaw_rad = s.estimate.pose.yaw_rad;
  state.has_covariance = s.estimate.has_covariance;
  std::copy(s.estimate.covariance.begin(), s.estimate.covariance.end(), state.pose_covariance);
  state.vx_mps = s.odometry_twist.vx_mps;
  state.vy_mps = s.odometry_twist.vy_mps;
  state.wz_radps = s.odometry_twist.wz_radps;
  state.has_twist_covariance = s.has_twist_covariance;
  std::copy(s.twist_covariance.begin(), s.twist_covariance.end(), state.twist_covariance);
  state.cmd_vx_mps = s.command_twist.vx_mps;
  state.cmd_vy_mps = s.command_twist.vy_mps;
  state.cmd_wz_radps = s.command_twist.wz_radps;
  state.gyro_wz_radps = s.gyro_wz_radps;
  state.odometry_residual = s.odometry_residual;
  state.localization_plugin = plugin.data();
  state.localization_swaps = s.localization_swaps;
  state.mode = to_msg(s.mode);
  state.fault_code = static_cast<std::uint16_t>(s.fault);
  state.fault_text = c_str(fault_code_name(s.fault));
  FaultDetail detail = s.fault_detail;
  detail.back() = '\0';
  state.fault_detail = detail.data();
  state.fault_count = s.fault_count;
  state.has_truth = s.has_truth;
  state.truth_x_m = s.truth.x_m;
  state.truth_y_m = s.truth.y_m;
  state.truth_yaw_rad = s.truth.yaw_rad;
  check(dds_write(dds_->state_writer, &state), "dds_write(robot state)");
  states_published_.fetch_add(1, std::memory_order_relaxed);

  std::array<swivel_msg_ModuleState, kMaxModules> module_buffer{};
  const std::uint32_t count = std::min(s.module_count, kMaxModules);
  for (std::uint32_t i = 0; i < count; ++i) {
    module_buffer[i] = {s.modules[i].steer_angle_rad, s.modules[i].steer_rate_cmd_radps,
                        s.modules[i].wheel_rate_cmd_radps, s.modules[i].wheel_rate_meas_radps};
  }
  swivel_msg_ModuleStates modules{};
  modules.robot_id = c_str(robot_id_);
  modules.cycle = s.cycle;
  modules.stamp_s = s.stamp_s;
  modules.modules._maximum = kMaxModules;
  modules.modules._length = count;
  modules.modules._buffer = module_buffer.data();
  modules.modules._release = false;
  check(dds_write(dds_->modules_writer, &modules), "dds_write(module states)");

  if (options_.ros2.enabled) publish_ros2_state(s);
}

void DdsBridge::publish_ros2_state(const StateSnapshot& s) {
  // ROS time of the same instant as stamp_s, mapped by the loop (rt::ClockOffset).
  const rt::RosTime ros_stamp = rt::to_ros_time(s.ros_stamp_ns);
  if (dds_->odom_writer != 0) {
    nav_msgs_msg_dds__Odometry_ odom{};
    odom.header.stamp.sec = ros_stamp.sec;
    odom.header.stamp.nanosec = ros_stamp.nanosec;
    odom.header.frame_id = c_str(odom_frame_);
    odom.child_frame_id = c_str(base_frame_);
    odom.pose.pose.position.x = s.estimate.pose.x_m;
    odom.pose.pose.position.y = s.estimate.pose.y_m;
    auto& q = odom.pose.pose.orientation;
    yaw_to_quaternion(s.estimate.pose.yaw_rad, q.x, q.y, q.z, q.w);
    to_ros_covariance(s.estimate.has_covariance ? &s.estimate.covariance : nullptr,
                      odom.pose.covariance);
    odom.twist.twist.linear.x = s.odometry_twist.vx_mps;
    odom.twist.twist.linear.y = s.odometry_twist.vy_mps;
    odom.twist.twist.angular.z = s.odometry_twist.wz_radps;
    to_ros_covariance(s.has_twist_covariance ? &s.twist_covariance : nullptr,
                      odom.twist.covariance);
    check(dds_write(dds_->odom_writer, &odom), "dds_write(odom)");
  }

  if (dds_->tf_writer != 0) {
    geometry_msgs_msg_dds__TransformStamped_ transform{};
    transform.header.stamp.sec = ros_stamp.sec;
    transform.header.stamp.nanosec = ros_stamp.nanosec;
    transform.header.frame_id = c_str(odom_frame_);
    transform.child_frame_id = c_str(base_frame_);
    transform.transform.translation.x = s.estimate.pose.x_m;
    transform.transform.translation.y = s.estimate.pose.y_m;
    auto& q = transform.transform.rotation;
    yaw_to_quaternion(s.estimate.pose.yaw_rad, q.x, q.y, q.z, q.w);
    tf2_msgs_msg_dds__TFMessage_ tf{};
    borrow(tf.transforms, &transform, 1);
    check(dds_write(dds_->tf_writer, &tf), "dds_write(tf)");
  }

  if (dds_->joint_states_writer != 0) {
    // Wheel joints, then steering joints, in module order: positions at stamp_s, velocities
    // the rates fitted over the twist window (absent until the loop has them).
    const std::uint32_t modules = std::min(s.module_count, kMaxModules);
    const auto wheels = std::min<std::size_t>(options_.ros2.wheel_joints.size(), modules);
    const auto steering = std::min<std::size_t>(options_.ros2.steering_joints.size(), modules);
    std::array<char*, std::size_t{2} * kMaxModules> names{};
    std::array<double, std::size_t{2} * kMaxModules> position{};
    std::array<double, std::size_t{2} * kMaxModules> velocity{};
    std::size_t n = 0;
    for (std::size_t i = 0; i < wheels; ++i, ++n) {
      names[n] = c_str(options_.ros2.wheel_joints[i]);
      position[n] = s.wheel_angle_rad[i];
      velocity[n] = s.wheel_rate_radps[i];
    }
    for (std::size_t i = 0; i < steering; ++i, ++n) {
      names[n] = c_str(options_.ros2.steering_joints[i]);
      const double offset = i < options_.ros2.steering_offsets_rad.size()
                                ? options_.ros2.steering_offsets_rad[i]
                                : 0.0;
      position[n] = s.steer_angle_rad[i] + offset;
      velocity[n] = s.steer_rate_radps[i];
    }
    sensor_msgs_msg_dds__JointState_ joints{};
    joints.header.stamp.sec = ros_stamp.sec;
    joints.header.stamp.nanosec = ros_stamp.nanosec;
    joints.header.frame_id = c_str("");
    const auto length = static_cast<std::uint32_t>(n);
    borrow(joints.name, names.data(), length);
    borrow(joints.position, position.data(), length);
    borrow(joints.velocity, velocity.data(), s.has_joint_rates ? length : 0);
    check(dds_write(dds_->joint_states_writer, &joints), "dds_write(joint states)");
  }
}

void DdsBridge::publish_diagnostics(const DiagnosticsSample& d) {
  swivel_msg_Diagnostics msg{};
  msg.robot_id = c_str(robot_id_);
  msg.stamp_s = monotonic_s();
  msg.uptime_s = d.uptime_s;
  msg.loop_rate_hz = d.loop_rate_hz;
  msg.measured_rate_hz = d.measured_rate_hz;
  msg.lateness = to_msg(d.lateness);
  msg.cycle_time = to_msg(d.cycle_time);
  msg.cycles = d.cycles;
  msg.overruns = d.overruns;
  msg.fault_count = d.fault_count;
  msg.fault_code = static_cast<std::uint16_t>(d.fault);
  msg.fault_text = c_str(fault_code_name(d.fault));
  msg.fault_detail = c_str(d.fault_detail);
  msg.commands_received = commands_received_.load(std::memory_order_relaxed);
  msg.commands_dropped = commands_dropped_.load(std::memory_order_relaxed);
  msg.hardware_plugin = c_str(d.hardware_plugin);
  msg.drivetrain_plugin = c_str(d.drivetrain_plugin);
  msg.localization_plugin = c_str(d.localization_plugin);
  msg.robot_model = c_str(d.robot_model);
  msg.reload_count = d.reload_count;
  msg.last_reload_ok = d.last_reload_ok;
  msg.last_reload_result = c_str(d.last_reload_result);
  msg.restart_required = d.restart_required;
  msg.publish_rate_hz = options_.publish_rate_hz;
  msg.achieved_publish_rate_hz = achieved_publish_rate_hz_.load();
  const std::string warnings = dds_warnings();
  msg.dds_warnings = c_str(warnings);
  check(dds_write(dds_->diagnostics_writer, &msg), "dds_write(diagnostics)");
  if (dds_->ros2_diagnostics_writer != 0) publish_ros2_diagnostics(d, warnings);
}

// One DiagnosticStatus for the robot: ERROR while the loop holds it in a safe stop, WARN for
// a transient fault (a command timeout, a rejected command) or a configuration that did not
// apply, OK otherwise; the values are Diagnostics' fields as text.
void DdsBridge::publish_ros2_diagnostics(const DiagnosticsSample& d,
                                         const std::string& dds_warnings) {
  constexpr std::uint8_t kOk = 0;
  constexpr std::uint8_t kWarn = 1;
  constexpr std::uint8_t kError = 2;
  std::uint8_t level = kOk;
  std::string message = "running";
  if (d.mode == LoopMode::kSafeStop) {
    level = kError;
  } else if (d.fault != FaultCode::kNone || !d.last_reload_ok || d.restart_required ||
             !dds_warnings.empty()) {
    level = kWarn;
  }
  if (d.fault != FaultCode::kNone) {
    message = std::string(d.mode == LoopMode::kSafeStop ? "safe stop: " : "") +
              fault_code_name(d.fault) +
              (d.fault_detail.empty() ? "" : " (" + d.fault_detail + ")");
  } else if (!d.last_reload_ok) {
    message = "running; last reload rejected";
  } else if (d.restart_required) {
    message = "running; a changed setting needs a restart";
  } else if (!dds_warnings.empty()) {
    message = "running; " + dds_warnings;
  }
  const char* mode = d.mode == LoopMode::kIdle          ? "idle"
                     : d.mode == LoopMode::kVelocity    ? "velocity"
                     : d.mode == LoopMode::kCalibration ? "calibration"
                                                        : "safe_stop";
  std::vector<std::pair<std::string, std::string>> values{
      {"mode", mode},
      {"fault", fault_code_name(d.fault)},
      {"fault_detail", d.fault_detail},
      {"fault_count", std::to_string(d.fault_count)},
      {"uptime_s", fmt::format("{:.1f}", d.uptime_s)},
      {"loop_rate_hz", fmt::format("{:g}", d.loop_rate_hz)},
      {"measured_rate_hz", fmt::format("{:.1f}", d.measured_rate_hz)},
      {"lateness_p99_us", fmt::format("{:.1f}", d.lateness.p99_us)},
      {"lateness_max_us", fmt::format("{:.1f}", d.lateness.max_us)},
      {"cycle_time_p99_us", fmt::format("{:.1f}", d.cycle_time.p99_us)},
      {"cycle_time_max_us", fmt::format("{:.1f}", d.cycle_time.max_us)},
      {"cycles", std::to_string(d.cycles)},
      {"overruns", std::to_string(d.overruns)},
      {"hardware_plugin", d.hardware_plugin},
      {"drivetrain_plugin", d.drivetrain_plugin},
      {"localization_plugin", d.localization_plugin},
      {"robot_model", d.robot_model},
      {"commands_received", std::to_string(commands_received_.load(std::memory_order_relaxed))},
      {"commands_dropped", std::to_string(commands_dropped_.load(std::memory_order_relaxed))},
      {"commands_stale", std::to_string(commands_stale_.load(std::memory_order_relaxed))},
      {"publish_failures", std::to_string(publish_failures_.load(std::memory_order_relaxed))},
      {"reload_count", std::to_string(d.reload_count)},
      {"last_reload", d.last_reload_result},
      {"restart_required", d.restart_required ? "true" : "false"},
      {"publish_rate_hz", fmt::format("{:g}", options_.publish_rate_hz)},
      {"achieved_publish_rate_hz", fmt::format("{:.1f}", achieved_publish_rate_hz_.load())},
      {"cmd_vel_type", options_.ros2.cmd_vel_stamped ? "geometry_msgs/msg/TwistStamped"
                                                     : "geometry_msgs/msg/Twist"},
      {"dds_warnings", dds_warnings}};
  if (dds_->sensors) {
    // The ROS 2 sensor topics' samples: a driver whose samples are all rejected shows here
    // before its silence stops the robot.
    const SensorCounters sensors = dds_->sensors->counters();
    if (options_.ros2.imu.enabled) {
      values.emplace_back("imu_samples", std::to_string(sensors.imu_received));
      values.emplace_back("imu_samples_rejected", std::to_string(sensors.imu_rejected));
    }
    if (options_.ros2.mocap_pose.enabled) {
      values.emplace_back("mocap_pose_samples", std::to_string(sensors.mocap_poses_received));
      values.emplace_back("mocap_pose_samples_rejected",
                          std::to_string(sensors.mocap_poses_rejected));
    }
    values.emplace_back("sensor_samples_dropped", std::to_string(sensors.dropped));
  }
  std::vector<diagnostic_msgs_msg_dds__KeyValue_> pairs(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    pairs[i].key = c_str(values[i].first);
    pairs[i].value = c_str(values[i].second);
  }
  const std::string name = "swiveld: " + robot_id_;
  diagnostic_msgs_msg_dds__DiagnosticStatus_ status{};
  status.level = level;
  status.name = c_str(name);
  status.message = c_str(message);
  status.hardware_id = c_str(robot_id_);
  borrow(status.values, pairs.data(), static_cast<std::uint32_t>(pairs.size()));

  diagnostic_msgs_msg_dds__DiagnosticArray_ array{};
  const rt::RosTime now = rt::to_ros_time(realtime_now_ns());
  array.header.stamp.sec = now.sec;
  array.header.stamp.nanosec = now.nanosec;
  array.header.frame_id = c_str("");
  borrow(array.status, &status, 1);
  check(dds_write(dds_->ros2_diagnostics_writer, &array), "dds_write(ros2 diagnostics)");
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

void DdsBridge::subscribe_loop(const std::stop_token& stop) {
  std::array<dds_attach_t, 8> triggered{};
  while (!stop.stop_requested()) {
    const dds_return_t n =
        dds_waitset_wait(dds_->waitset, triggered.data(), triggered.size(), DDS_MSECS(200));
    if (n < 0) {
      spdlog::warn("dds: waitset failed: {}", dds_strretcode(n));
      return;
    }
    try {
      take_commands();
      take_ros2_commands();
      take_motion_capture();
      take_requests();
      take_set_poses();
      take_ros2_initialposes();
      if (dds_->sensors) dds_->sensors->take();
      if (dds_->cmd_vel_check) dds_->cmd_vel_check->take();
    } catch (const std::exception& e) {
      spdlog::warn("dds: command handling failed: {}", e.what());
    }
  }
}

void DdsBridge::deliver_command(const Twist2& twist) {
  VelocityCommand command;
  command.twist = twist;
  command.received_s = monotonic_s();
  command.sequence = ++next_command_sequence_;
  if (callbacks_.on_command && callbacks_.on_command(command)) {
    commands_received_.fetch_add(1, std::memory_order_relaxed);
  } else {
    commands_dropped_.fetch_add(1, std::memory_order_relaxed);
  }
}

void DdsBridge::take_commands() {
  take_all<swivel_msg_VelocityCommand>(
      dds_->command_reader, [this](const swivel_msg_VelocityCommand& c) {
        if (c.robot_id == nullptr || robot_id_ != c.robot_id) {
          commands_ignored_.fetch_add(1, std::memory_order_relaxed);
          return;
        }
        deliver_command({c.vx_mps, c.vy_mps, c.wz_radps});
      });
}

void DdsBridge::take_ros2_commands() {
  if (dds_->cmd_vel_reader == 0) return;
  // ROS 2 topics are per robot through their namespace: no robot id to check.
  if (!options_.ros2.cmd_vel_stamped) {
    take_all<geometry_msgs_msg_dds__Twist_>(
        dds_->cmd_vel_reader, [this](const geometry_msgs_msg_dds__Twist_& t) {
          deliver_command({t.linear.x, t.linear.y, t.angular.z});
        });
    return;
  }
  take_all<geometry_msgs_msg_dds__TwistStamped_>(
      dds_->cmd_vel_reader, [this](const geometry_msgs_msg_dds__TwistStamped_& m) {
        const auto& stamp = m.header.stamp;
        if (stamp.sec != 0 || stamp.nanosec != 0) {
          // A stamp too far from now either way (an old command, a sender's clock off) is
          // stale; a zero stamp is "now", as ros2_controllers' diff_drive_controller takes it.
          const std::int64_t stamp_ns =
              static_cast<std::int64_t>(stamp.sec) * 1'000'000'000 + stamp.nanosec;
          const double age_s = 1e-9 * static_cast<double>(realtime_now_ns() - stamp_ns);
          if (!(std::abs(age_s) <= options_.ros2.cmd_vel_max_age_s)) {
            if (commands_stale_.fetch_add(1, std::memory_order_relaxed) == 0) {
              spdlog::warn(
                  "dds: {}: dropped a TwistStamped {:.3f} s from now (more than "
                  "cmd_vel_max_age_s {} s); further ones are counted in diagnostics",
                  options_.ros2.cmd_vel_topic(), age_s, options_.ros2.cmd_vel_max_age_s);
            }
            return;
          }
        } else if (!warned_zero_stamp_) {
          warned_zero_stamp_ = true;
          spdlog::warn("dds: {}: TwistStamped with a zero stamp taken as sent now",
                       options_.ros2.cmd_vel_topic());
        }
        deliver_command({m.twist.linear.x, m.twist.linear.y, m.twist.angular.z});
      });
}

void DdsBridge::take_motion_capture() {
  take_all<swivel_msg_MotionCapture>(
      dds_->motion_capture_reader, [this](const swivel_msg_MotionCapture& m) {
        if (m.robot_id == nullptr || robot_id_ != m.robot_id) return;
        MotionCaptureSample sample;
        sample.valid = true;
        sample.stamp_s = m.stamp_s > 0.0 ? m.stamp_s : monotonic_s();
        sample.pose = {m.x_m, m.y_m, m.yaw_rad};
        if (callbacks_.on_motion_capture && callbacks_.on_motion_capture(sample)) {
          motion_captures_received_.fetch_add(1, std::memory_order_relaxed);
        }
      });
}

void DdsBridge::take_requests() {
  take_all<swivel_msg_Request>(dds_->request_reader, [this](const swivel_msg_Request& r) {
    if (r.robot_id == nullptr || robot_id_ != r.robot_id) return;
    requests_received_.fetch_add(1, std::memory_order_relaxed);
    if (!callbacks_.on_request) return;
    RequestSample sample;
    sample.verb = r.verb != nullptr ? r.verb : "";
    sample.argument = r.argument != nullptr ? r.argument : "";
    sample.request_id = r.request_id;
    callbacks_.on_request(sample);
  });
}

void DdsBridge::take_set_poses() {
  take_all<swivel_msg_SetPose>(dds_->set_pose_reader, [this](const swivel_msg_SetPose& p) {
    if (p.robot_id == nullptr || robot_id_ != p.robot_id) return;
    requests_received_.fetch_add(1, std::memory_order_relaxed);
    if (!callbacks_.on_set_pose) return;
    SetPoseSample sample;
    sample.request_id = p.request_id;
    sample.pose.pose = {p.x_m, p.y_m, p.yaw_rad};
    sample.pose.has_covariance = p.has_covariance;
    if (p.has_covariance) {
      // sigma * |sigma|: a negative sigma stays visible to the daemon's check as a negative
      // variance instead of hiding behind its square.
      const auto variance = [](double sigma) { return sigma * std::abs(sigma); };
      sample.pose.covariance = {variance(p.sigma_x_m),    0.0, 0.0, 0.0,
                                variance(p.sigma_y_m),    0.0, 0.0, 0.0,
                                variance(p.sigma_yaw_rad)};
    }
    sample.source = kSetPoseTopic;
    callbacks_.on_set_pose(sample);
  });
}

void DdsBridge::take_ros2_initialposes() {
  if (dds_->initialpose_reader == 0) return;
  take_all<geometry_msgs_msg_dds__PoseWithCovarianceStamped_>(
      dds_->initialpose_reader, [this](const geometry_msgs_msg_dds__PoseWithCovarianceStamped_& m) {
        requests_received_.fetch_add(1, std::memory_order_relaxed);
        const std::string frame = m.header.frame_id != nullptr ? m.header.frame_id : "";
        if (!frame.empty() && frame != odom_frame_) {
          spdlog::warn("{}: pose in frame '{}' ignored: swiveld estimates the pose in '{}'",
                       options_.ros2.initialpose_topic(), frame, odom_frame_);
          return;
        }
        if (!callbacks_.on_set_pose) return;
        const auto& q = m.pose.pose.orientation;
        SetPoseSample sample;
        sample.wants_reply = false;
        sample.source = options_.ros2.initialpose_topic();
        sample.pose.pose = {m.pose.pose.position.x, m.pose.pose.position.y,
                            quaternion_to_yaw(q.x, q.y, q.z, q.w)};
        // (x, y, yaw) sit at rows/columns (0, 1, 5) of ROS's 6x6; all zero means "none".
        constexpr std::array<int, 3> kIndex{0, 1, 5};
        bool any = false;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) {
            const double v = m.pose.covariance[kIndex[r] * 6 + kIndex[c]];
            sample.pose.covariance[r * 3 + c] = v;
            any = any || v != 0.0;
          }
        }
        sample.pose.has_covariance = any;
        callbacks_.on_set_pose(sample);
      });
}

}  // namespace swivel::dds
