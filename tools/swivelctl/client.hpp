// SPDX-License-Identifier: Apache-2.0
#pragma once
// swivelctl's view of the DDS domain: one participant, readers and writers of Swivel's
// topics, and waiting for samples with a deadline.

#include <dds/dds.h>

#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "swivel/dds/topics.hpp"

namespace swivel::ctl {

/// Set by SIGINT/SIGTERM: every wait returns early.
bool interrupted() noexcept;
void install_signal_handlers();

class Client {
 public:
  /// Joins `domain_id` with tool_config_uri() (CYCLONEDDS_URI or the loopback file).
  explicit Client(std::uint32_t domain_id);

  /// A reader with Swivel's default QoS (reliable, keep last 10), or with `qos`.
  dds_entity_t reader(const dds_topic_descriptor_t* descriptor, const char* topic,
                      const dds_qos_t* qos = nullptr);
  dds_entity_t writer(const dds_topic_descriptor_t* descriptor, const char* topic);

  /// Waits until one of `readers` has data or `timeout` passes; false on timeout or
  /// interruption.
  bool wait_for_data(std::initializer_list<dds_entity_t> readers,
                     std::chrono::duration<double> timeout);

  /// Takes every valid sample of `reader`, calling `fn(const void* sample)`.
  static void take(dds_entity_t reader, const std::function<void(const void*)>& fn);

  /// Waits until `writer` matches a reader; false on timeout or interruption.
  static bool wait_for_match(dds_entity_t writer, std::chrono::duration<double> timeout);

 private:
  dds::Participant participant_;
  std::map<dds_entity_t, dds_entity_t> conditions_;  ///< reader -> its read condition
};

/// The robot a command goes to: `requested` if it publishes state within `timeout`, or the
/// only robot that does when `requested` is empty. Throws std::runtime_error with a
/// user-facing message otherwise (none, or several and no --robot).
/// "3 s", "0.5 s": a duration for messages.
std::string seconds_text(std::chrono::duration<double> d);

std::string resolve_robot(Client& client, const std::string& requested,
                          std::chrono::duration<double> timeout);

}  // namespace swivel::ctl
