// SPDX-License-Identifier: Apache-2.0
#pragma once
// Requests that arrive over DDS (Request: reload, clear, calibrate; SetPose, also from ROS 2
// initialpose): queued by the DDS subscriber thread, answered one at a time, in the order
// they came, by the main thread, each with a Reply carrying its request id.

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <variant>

#include "swivel/dds/bridge.hpp"

namespace swivel::daemon {

/// The bounded queue between the subscriber thread and the main thread.
class RequestQueue {
 public:
  using Request = std::variant<dds::RequestSample, dds::SetPoseSample>;
  static constexpr std::size_t kMaxPending = 64;

  /// Any thread. Queues `request` and returns std::nullopt; when kMaxPending requests are
  /// waiting already, returns the reply that refuses it at once instead (std::nullopt too
  /// for a set-pose that wants no reply).
  std::optional<dds::ReplySample> push(Request request);

  /// Any thread. The oldest request, if any.
  std::optional<Request> pop();

 private:
  std::mutex mutex_;
  std::deque<Request> pending_;
};

/// Who answers each verb. Main thread; each returns the reply to send.
struct RequestHandlers {
  std::function<dds::ReplySample()> reload;
  std::function<dds::ReplySample(std::uint64_t request_id)> clear;
  std::function<dds::ReplySample(const std::string& argument)> calibrate;
  std::function<dds::ReplySample(const dds::SetPoseSample&)> set_pose;
};

/// Answers one Request by its verb (refused while `stopping` or for an unknown verb), sets
/// the reply's request id and verb, and logs the outcome.
dds::ReplySample route_request(const dds::RequestSample& request, bool stopping,
                               const RequestHandlers& handlers);

/// Main thread. Answers every queued request (refused once `stopping`); `publish` sends each reply
/// that is wanted (set-poses may want none) and may throw (logged).
void answer_requests(RequestQueue& queue, const std::atomic<bool>& stopping,
                     const RequestHandlers& handlers,
                     const std::function<void(const dds::ReplySample&)>& publish);

}  // namespace swivel::daemon
