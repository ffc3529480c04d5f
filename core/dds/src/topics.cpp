// SPDX-License-Identifier: Apache-2.0
#include "swivel/dds/topics.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <set>

#include "swivel/shipped_config.hpp"

namespace swivel::dds {

dds_return_t check(dds_return_t rc, const char* what) {
  if (rc < 0) {
    throw DdsError(std::string(what) + ": " + dds_strretcode(rc));
  }
  return rc;
}

namespace {

QosPtr make_qos(int depth, dds_reliability_kind_t reliability, int max_depth = 100) {
  QosPtr qos(dds_create_qos());
  dds_qset_reliability(qos.get(), reliability, DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, std::clamp(depth, 1, max_depth));
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos.get(), 1, &xcdr1);
  return qos;
}

// Cyclone refuses to create a domain twice in one process; the first creator's
// configuration holds for every later participant of that domain in this process.
void ensure_domain(std::uint32_t domain_id, const std::string& config_uri) {
  static std::mutex mutex;
  static std::set<std::uint32_t> created;
  const std::scoped_lock lock(mutex);
  if (created.contains(domain_id)) return;
  const dds_entity_t domain = dds_create_domain(domain_id, config_uri.c_str());
  if (domain < 0 && domain != DDS_RETCODE_PRECONDITION_NOT_MET) {
    check(domain, ("dds_create_domain(" + config_uri + ")").c_str());
  }
  // Kept for the life of the process: deleting it would delete other users' participants.
  created.insert(domain_id);
}

}  // namespace

QosPtr default_qos(int depth) { return make_qos(depth, DDS_RELIABILITY_RELIABLE); }

QosPtr best_effort_qos(int depth) { return make_qos(depth, DDS_RELIABILITY_BEST_EFFORT); }

QosPtr run_samples_qos() {
  return make_qos(kRunSamplesHistoryDepth, DDS_RELIABILITY_RELIABLE, kRunSamplesHistoryDepth);
}

Participant::Participant(const ParticipantOptions& options) {
  if (!options.config_uri.empty()) ensure_domain(options.domain_id, options.config_uri);
  handle_ =
      check(dds_create_participant(options.domain_id, nullptr, nullptr), "dds_create_participant");
}

Participant::~Participant() {
  if (handle_ > 0) dds_delete(handle_);
}

ResolvedConfig resolve_config(const std::string& file_uri) {
  const char* env = std::getenv("CYCLONEDDS_URI");
  if (env != nullptr && *env != '\0') {
    std::string description = std::string("CYCLONEDDS_URI=") + env + " (environment";
    if (!file_uri.empty()) description += "; it overrides dds.config " + file_uri;
    return {"", description + ")"};
  }
  if (!file_uri.empty()) return {file_uri, "dds.config " + file_uri + " (CYCLONEDDS_URI unset)"};
  const std::string loopback = "file://" + shipped_config_file("dds/loopback.xml").string();
  return {loopback, loopback + " (CYCLONEDDS_URI unset)"};
}

std::string tool_config_uri() { return resolve_config().uri; }

std::string describe_tool_config() { return resolve_config().description; }

dds_entity_t create_topic(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
                          const char* name) {
  return check(dds_create_topic(participant, descriptor, name, nullptr, nullptr),
               (std::string("dds_create_topic(") + name + ")").c_str());
}

}  // namespace swivel::dds
