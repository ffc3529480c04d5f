// SPDX-License-Identifier: Apache-2.0
#include "client.hpp"

#include <csignal>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "swivel.h"

namespace swivel::ctl {

namespace {

volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void on_signal(int) { g_interrupted = 1; }

dds_duration_t to_dds(std::chrono::duration<double> d) {
  return d.count() <= 0.0 ? 0 : static_cast<dds_duration_t>(d.count() * 1e9);
}

}  // namespace

bool interrupted() noexcept { return g_interrupted != 0; }

void install_signal_handlers() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

Client::Client(std::uint32_t domain_id) : participant_({domain_id, dds::tool_config_uri()}) {}

std::string seconds_text(std::chrono::duration<double> d) {
  std::ostringstream out;
  out << d.count() << " s";
  return out.str();
}

dds_entity_t Client::reader(const dds_topic_descriptor_t* descriptor, const char* topic,
                            const dds_qos_t* qos) {
  const dds_entity_t t = dds::create_topic(participant_.handle(), descriptor, topic);
  const dds::QosPtr default_qos = dds::default_qos(10);
  const dds_entity_t r =
      dds::check(dds_create_reader(participant_.handle(), t,
                                   qos != nullptr ? qos : default_qos.get(), nullptr),
                 "dds_create_reader");
  conditions_[r] =
      dds::check(dds_create_readcondition(r, DDS_ANY_STATE), "dds_create_readcondition");
  return r;
}

dds_entity_t Client::writer(const dds_topic_descriptor_t* descriptor, const char* topic) {
  const dds_entity_t t = dds::create_topic(participant_.handle(), descriptor, topic);
  const dds::QosPtr qos = dds::default_qos(10);
  return dds::check(dds_create_writer(participant_.handle(), t, qos.get(), nullptr),
                    "dds_create_writer");
}

bool Client::wait_for_data(std::initializer_list<dds_entity_t> readers,
                           std::chrono::duration<double> timeout) {
  // A waitset per call: readers not asked about must not wake us up.
  const dds_entity_t waitset =
      dds::check(dds_create_waitset(participant_.handle()), "dds_create_waitset");
  for (const dds_entity_t r : readers) {
    dds::check(dds_waitset_attach(waitset, conditions_.at(r), r), "dds_waitset_attach");
  }
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  dds_attach_t triggered[8];
  bool ready = false;
  while (!ready && !interrupted()) {
    const auto left = deadline - std::chrono::steady_clock::now();
    if (left <= std::chrono::steady_clock::duration::zero()) break;
    // Short slices so that Ctrl-C is noticed promptly.
    const auto slice =
        std::min<std::chrono::duration<double>>(left, std::chrono::milliseconds(100));
    ready = dds_waitset_wait(waitset, triggered, 8, to_dds(slice)) > 0;
  }
  dds_delete(waitset);
  return ready;
}

void Client::take(dds_entity_t reader, const std::function<void(const void*)>& fn) {
  void* samples[16];
  dds_sample_info_t infos[16];
  for (;;) {
    samples[0] = nullptr;
    const dds_return_t n = dds_take(reader, samples, infos, 16, 16);
    if (n <= 0) return;
    for (dds_return_t i = 0; i < n; ++i) {
      if (infos[i].valid_data) fn(samples[i]);
    }
    dds_return_loan(reader, samples, n);
    if (n < 16) return;
  }
}

bool Client::wait_for_match(dds_entity_t writer, std::chrono::duration<double> timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!interrupted() && std::chrono::steady_clock::now() < deadline) {
    dds_publication_matched_status_t status{};
    if (dds_get_publication_matched_status(writer, &status) == DDS_RETCODE_OK &&
        status.current_count > 0) {
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

std::string resolve_robot(Client& client, const std::string& requested,
                          std::chrono::duration<double> timeout) {
  const dds_entity_t reader = client.reader(&swivel_msg_RobotState_desc, dds::kRobotStateTopic);
  std::set<std::string> seen;
  const auto start = std::chrono::steady_clock::now();
  std::optional<std::chrono::steady_clock::time_point> first_seen;
  while (!interrupted()) {
    const auto now = std::chrono::steady_clock::now();
    // Once one robot answered, listen a little longer to notice a fleet.
    if (first_seen && now - *first_seen > std::chrono::milliseconds(300)) break;
    const auto left = timeout - (now - start);
    if (left <= std::chrono::duration<double>::zero()) break;
    if (!client.wait_for_data({reader}, std::min<std::chrono::duration<double>>(
                                            left, std::chrono::milliseconds(100)))) {
      continue;
    }
    Client::take(reader, [&](const void* p) {
      seen.insert(static_cast<const swivel_msg_RobotState*>(p)->robot_id);
    });
    if (!requested.empty() && seen.contains(requested)) return requested;
    if (!seen.empty() && !first_seen) first_seen = std::chrono::steady_clock::now();
  }
  if (interrupted()) throw std::runtime_error("interrupted");
  if (seen.empty()) {
    throw std::runtime_error(
        "no swiveld answered within " + seconds_text(timeout) +
        " (no robot state on the domain; DDS configuration: " + dds::describe_tool_config() + ")");
  }
  std::string list;
  for (const auto& id : seen) list += (list.empty() ? "" : ", ") + id;
  if (!requested.empty()) {
    throw std::runtime_error("robot '" + requested + "' did not answer within " +
                             seconds_text(timeout) + "; robots on the domain: " + list);
  }
  if (seen.size() > 1) {
    throw std::runtime_error("several robots on the domain (" + list +
                             "): choose one with --robot");
  }
  return *seen.begin();
}

}  // namespace swivel::ctl
