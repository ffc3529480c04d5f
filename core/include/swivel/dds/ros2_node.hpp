// SPDX-License-Identifier: Apache-2.0
#pragma once
// The daemon as a ROS 2 node: what a ROS 2 participant announces so that `ros2 node list`
// shows the node and `ros2 topic info -v` names it as the owner of its topics. rmw_cyclonedds
// puts "enclave=<enclave>;" in the participant's USER_DATA and publishes, on the DDS topic
// ros_discovery_info, an rmw_dds_common/msg/ParticipantEntitiesInfo listing each node of the
// participant with the GIDs of its readers and writers. Start-up code; not real-time safe.

#include <dds/dds.h>

#include <string>
#include <vector>

namespace swivel::dds {

/// USER_DATA of the daemon's participant with ROS 2 enabled: the root enclave.
inline constexpr const char* kRos2ParticipantUserData = "enclave=/;";

/// The node this participant hosts and the endpoints it owns.
struct Ros2NodeEntities {
  std::string node_namespace;         ///< absolute: "/" or "/robot1"
  std::string node_name;              ///< e.g. "swiveld"
  std::vector<dds_entity_t> readers;  ///< the node's subscriptions (0 entries are skipped)
  std::vector<dds_entity_t> writers;  ///< the node's publishers (0 entries are skipped)
};

/// Creates the ros_discovery_info writer on `participant` with the QoS rmw_cyclonedds uses
/// (reliable, transient local, keep last 1, plain CDR: a ROS tool started later still gets
/// it) and writes the participant's one node. Returns the writer, which lives as long as
/// the participant. @throws DdsError
dds_entity_t announce_ros2_node(dds_entity_t participant, const Ros2NodeEntities& node);

}  // namespace swivel::dds
