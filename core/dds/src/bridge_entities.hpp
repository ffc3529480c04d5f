// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the bridge's sources share (private to swivel_dds): the DDS entities DdsBridge owns and
// the helpers that fill idlc's C samples. The bridge is split by thread and by what it
// writes (bridge.cpp, bridge_publisher.cpp, bridge_ros2_state.cpp, bridge_diagnostics.cpp,
// bridge_subscriber.cpp), and every part reaches its writers and readers through Entities.
// Not real-time safe.

#include <dds/dds.h>
#include <time.h>

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>

#include "swivel/dds/bridge.hpp"
#include "swivel/dds/cmd_vel_type_check.hpp"
#include "swivel/dds/options.hpp"
#include "swivel/dds/ros2_node.hpp"
#include "swivel/dds/sensor_inputs.hpp"
#include "swivel/dds/topics.hpp"

namespace swivel::dds {

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

// idlc's C types hold strings as char*, in samples that are only written too: Cyclone reads
// through the pointer and never writes.
// NOLINTBEGIN(cppcoreguidelines-pro-type-const-cast)
inline char* c_str(const std::string& s) { return const_cast<char*>(s.c_str()); }
inline char* c_str(const char* s) { return const_cast<char*>(s); }
// NOLINTEND(cppcoreguidelines-pro-type-const-cast)

// CLOCK_REALTIME now, ns: ROS time for what the bridge stamps itself (diagnostics, the
// stale check of stamped commands); loop samples carry the loop's own mapping.
inline std::int64_t realtime_now_ns() {
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

}  // namespace swivel::dds
