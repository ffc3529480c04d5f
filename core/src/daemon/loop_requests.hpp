// SPDX-License-Identifier: Apache-2.0
#pragma once
// The requests answered by the real-time loop itself, asked from the main thread: clear
// (with the hardware re-activated first when it left its active state) and set-pose. Each
// is handed to the loop, which answers at its next cycle (ControlLoop::take_reply()).
//
// Main thread only, while the loop runs. Not real-time safe (waits up to 1 s for the loop).

#include <cstdint>
#include <string>

#include "swivel/dds/bridge.hpp"
#include "swivel/plugin/hardware.hpp"

namespace swivel::rt {
class ControlLoop;
struct LoopReply;
}  // namespace swivel::rt

namespace swivel::daemon {

class LoopRequests {
 public:
  /// `hardware` is the loop's hardware plugin, named `hardware_plugin` in replies.
  LoopRequests(rt::ControlLoop& loop, Hardware& hardware, std::string hardware_plugin);

  /// The clear verb: leaves the active fault when its cause is gone, refused with the cause
  /// while it persists; a hardware in its error state is re-activated first, with the
  /// loop's calls to it paused at a cycle boundary.
  dds::ReplySample clear(std::uint64_t request_id);

  /// Sets the pose estimate through the active localization's hand-over at a cycle
  /// boundary; refused (nothing changes) while `stopping`, for a non-finite pose or
  /// covariance, a negative variance, or when the plugin refuses. Logs the outcome.
  dds::ReplySample set_pose(const dds::SetPoseSample& request, bool stopping);

 private:
  bool wait_for_reply(std::uint64_t id, rt::LoopReply& out);

  rt::ControlLoop& loop_;
  Hardware& hardware_;
  std::string hardware_plugin_;
  std::uint64_t next_id_ = 0;  // ids of requests to the loop
};

}  // namespace swivel::daemon
