// SPDX-License-Identifier: Apache-2.0
#pragma once
// Helpers for the DDS tests: a reader/writer on their own participant, and waiting with a
// generous deadline (discovery on a loaded machine can take seconds).

#include <dds/dds.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>

#include "swivel/dds/topics.hpp"

namespace swivel::dds::test {

inline constexpr auto kDiscoveryTimeout = std::chrono::seconds(10);

// Run outside ctest (no CYCLONEDDS_URI), the tests and the swivelctl they start still stay
// on loopback.
inline const bool loopback_only = [] {
  const std::string uri = tool_config_uri();
  // At static initialisation, before the test starts a thread.
  if (!uri.empty()) ::setenv("CYCLONEDDS_URI", uri.c_str(), 0);  // NOLINT(concurrency-mt-unsafe)
  return true;
}();

/// Polls `done` every 5 ms until it is true or `timeout` passes; returns its last value.
inline bool wait_for(const std::function<bool()>& done,
                     std::chrono::milliseconds timeout = kDiscoveryTimeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

/// A robot id no other test process on the domain uses.
inline std::string unique_robot_id(const std::string& stem) {
  return stem + "_" + std::to_string(::getpid());
}

/// Takes one valid sample of type T from `reader` into `out` (a deep copy through `copy`).
template <typename T, typename Copy>
bool take_one(dds_entity_t reader, Copy&& copy) {
  void* samples[1] = {nullptr};
  dds_sample_info_t info{};
  const dds_return_t n = dds_take(reader, samples, &info, 1, 1);
  if (n <= 0) return false;
  const bool valid = info.valid_data;
  if (valid) copy(*static_cast<const T*>(samples[0]));
  dds_return_loan(reader, samples, n);
  return valid;
}

inline bool publication_matched(dds_entity_t writer) {
  dds_publication_matched_status_t status{};
  return dds_get_publication_matched_status(writer, &status) == DDS_RETCODE_OK &&
         status.current_count > 0;
}

inline bool subscription_matched(dds_entity_t reader) {
  dds_subscription_matched_status_t status{};
  return dds_get_subscription_matched_status(reader, &status) == DDS_RETCODE_OK &&
         status.current_count > 0;
}

}  // namespace swivel::dds::test
