// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the real-time loop hands out for recording a run: one RunSample every
// LoopOptions::run_sample_rate_hz, through a lock-free SPSC ring (ControlLoop::take_run_sample()),
// so that a recorder off the loop gets every sample and not just the newest state. Trivially
// copyable by construction.

#include <array>
#include <cstdint>
#include <type_traits>

#include "swivel/rt/state_snapshot.hpp"
#include "swivel/types.hpp"

namespace swivel {

/// One run-log row's worth of the loop's state at one cycle.
struct RunSample {
  /// Counts every sample the loop produced, from 1 with no gaps, including those it could
  /// not hand over because the ring was full: a jump tells the consumer how many were lost.
  std::uint64_t sequence = 0;
  std::uint64_t cycle = 0;  ///< the loop cycle sampled
  double stamp_s = 0.0;     ///< monotonic time of the cycle's reading, s
  /// The velocity command the loop followed in that cycle, before the robot model's limits
  /// (zero when it was stopping the robot or had no command), robot frame: what a run log's
  /// command columns hold, since the model-gap replay applies the model's limits itself.
  Twist2 command_twist;
  std::uint32_t module_count = 0;
  std::array<double, kMaxModules> wheel_angle_rad{};  ///< cumulative encoder angles, rad
  std::array<double, kMaxModules> steer_angle_rad{};  ///< measured steering angles, rad (swpc)
  double gyro_wz_radps = 0.0;                         ///< measured yaw rate, rad/s
  /// The pose the hardware reports as the truth (a simulator's ground truth, at stamp_s), or
  /// else the newest motion-capture sample the loop took since the previous run sample.
  bool has_truth = false;
  Pose2 truth;                         ///< world frame
  double truth_stamp_s = 0.0;          ///< monotonic time the truth refers to, s
  Pose2 estimate;                      ///< the localization's pose estimate, world frame
  FaultCode fault = FaultCode::kNone;  ///< active fault in that cycle
  LoopMode mode = LoopMode::kIdle;
};

static_assert(std::is_trivially_copyable_v<RunSample>);

}  // namespace swivel
