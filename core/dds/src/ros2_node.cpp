// SPDX-License-Identifier: Apache-2.0
#include "swivel/dds/ros2_node.hpp"

#include <algorithm>
#include <cstddef>
#include <iterator>
#include <string>
#include <vector>

#include "rmw_dds_common.h"
#include "swivel/dds/topics.hpp"

namespace swivel::dds {

namespace {

// A ROS 2 GID is the entity's DDS GUID, as rmw_cyclonedds derives it.
rmw_dds_common_msg_dds__Gid_ gid_of(dds_entity_t entity) {
  dds_guid_t guid{};
  check(dds_get_guid(entity, &guid), "dds_get_guid");
  rmw_dds_common_msg_dds__Gid_ gid{};
  static_assert(sizeof gid.data == sizeof guid.v);
  std::copy(std::begin(guid.v), std::end(guid.v), std::begin(gid.data));
  return gid;
}

std::vector<rmw_dds_common_msg_dds__Gid_> gids_of(const std::vector<dds_entity_t>& entities) {
  std::vector<rmw_dds_common_msg_dds__Gid_> gids;
  for (const dds_entity_t entity : entities) {
    if (entity != 0) gids.push_back(gid_of(entity));
  }
  return gids;
}

// The message's string<256> fields are char arrays in idlc's C types.
template <std::size_t N>
void copy_bounded(const std::string& text, char (&field)[N], const char* what) {
  if (text.size() >= N) {
    throw DdsError(std::string("ros_discovery_info: the ") + what + " '" + text +
                   "' is longer than " + std::to_string(N - 1) + " characters");
  }
  std::copy(text.begin(), text.end(), std::begin(field));
  field[text.size()] = '\0';
}

template <typename Sequence, typename Element>
void borrow(Sequence& sequence, std::vector<Element>& elements) {
  sequence._maximum = static_cast<std::uint32_t>(elements.size());
  sequence._length = sequence._maximum;
  sequence._buffer = elements.data();
  sequence._release = false;
}

}  // namespace

dds_entity_t announce_ros2_node(dds_entity_t participant, const Ros2NodeEntities& node) {
  const dds_entity_t topic = create_topic(
      participant, &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc, kRosDiscoveryInfoTopic);
  const QosPtr qos(dds_create_qos());
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos.get(), 1, &xcdr1);
  const dds_entity_t writer = check(dds_create_writer(participant, topic, qos.get(), nullptr),
                                    "dds_create_writer(ros_discovery_info)");

  std::vector<rmw_dds_common_msg_dds__Gid_> readers = gids_of(node.readers);
  std::vector<rmw_dds_common_msg_dds__Gid_> writers = gids_of(node.writers);
  std::vector<rmw_dds_common_msg_dds__NodeEntitiesInfo_> nodes(1);
  copy_bounded(node.node_namespace, nodes[0].node_namespace, "node namespace");
  copy_bounded(node.node_name, nodes[0].node_name, "node name");
  borrow(nodes[0].reader_gid_seq, readers);
  borrow(nodes[0].writer_gid_seq, writers);

  rmw_dds_common_msg_dds__ParticipantEntitiesInfo_ info{};
  info.gid = gid_of(participant);
  borrow(info.node_entities_info_seq, nodes);
  check(dds_write(writer, &info), "dds_write(ros_discovery_info)");
  return writer;
}

}  // namespace swivel::dds
