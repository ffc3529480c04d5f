// SPDX-License-Identifier: Apache-2.0
#pragma once
// Shutdown's first step: the robot brought to rest by the loop itself (commands ignored,
// the twist ramped to zero within the controlled stop's limits) while the loop still runs.
// Not real-time safe: the calling thread waits.

#include "swivel/daemon/daemon_config.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::rt {
class ControlLoop;
}

namespace swivel::daemon {

/// Requests the loop's controlled stop (a no-op when requested already) and waits until the
/// robot is commanded to zero and measured still, or at most the ramp's time at the limits
/// (the model's `limits:`, `stop` on the axes it leaves open) plus 1 s for the drives' lag.
/// Logs how long it took and, with the simulator's ground truth, how far the robot went.
void bring_to_rest(rt::ControlLoop& loop, const MotionLimits& limits,
                   const ControlledStopConfig& stop) noexcept;

}  // namespace swivel::daemon
