// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's last stage: what the non-real-time side sees. The state at the end of each cycle
// goes into a seqlock SnapshotBuffer that any thread reads without a lock, and, when one is
// due, a RunSample into the recorder's ring (RunSampleStage). The other stages write their
// share of the cycle's state (state()) before publish() completes and hands it out; a cycle
// with the hardware paused publishes the stopped robot without a reading.
//
// Any thread may call latest() and the run samples' take side; everything else runs on the
// loop thread. Real-time safe: no allocation, no lock, no I/O; noexcept.

#include <cstdint>
#include <span>

#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/rt/run_sample_stage.hpp"
#include "swivel/rt/snapshot_buffer.hpp"
#include "swivel/rt/state_snapshot.hpp"

namespace swivel::rt {

/// The cycle's share of the snapshot that publish() fills in itself.
struct CycleReport {
  double now_s = 0.0;
  std::int64_t ros_stamp_ns = 0;           ///< now_s in ROS time
  Twist2 applied;                          ///< the twist applied after limits and kinematics
  const HardwareState* reading = nullptr;  ///< the cycle's reading (its angles are published)
  bool reading_ok = false;                 ///< the reading is usable (its gyro is published)
  std::uint32_t module_count = 0;
  bool stopping = false;  ///< the controlled stop was taken
};

// Its buffers are cache-line aligned so that the loop and the readers do not share lines:
// the padding is the point.
// NOLINTNEXTLINE(clang-analyzer-optin.performance.Padding)
class PublishStage {
 public:
  /// `run_sample_period_s`: between two run samples, 0 for none; `loop_period_s` the loop's.
  PublishStage(double run_sample_period_s, double loop_period_s) noexcept
      : run_samples_(run_sample_period_s, loop_period_s) {}

  /// Any thread. The state at the end of the newest cycle.
  [[nodiscard]] StateSnapshot latest() const noexcept { return snapshot_.read(); }

  /// The run samples (the recording thread takes them, the loop notes and publishes them).
  [[nodiscard]] RunSampleStage& run_samples() noexcept { return run_samples_; }
  [[nodiscard]] const RunSampleStage& run_samples() const noexcept { return run_samples_; }

  /// Loop thread. The state being built: the last published one until publish().
  [[nodiscard]] StateSnapshot& state() noexcept { return state_; }
  [[nodiscard]] const StateSnapshot& state() const noexcept { return state_; }

  /// Loop thread. Hands state() out as it is (the loop's first state).
  void write() noexcept { snapshot_.write(state_); }

  /// Loop thread. A cycle without a hardware call: the robot stopped, no twist, no reading.
  void publish_paused(double now_s, std::int64_t ros_stamp_ns) noexcept;

  /// Loop thread, at the end of a cycle: completes state() with `report`, the drivetrain's
  /// module states and the hardware's ground truth, publishes it and hands out a run sample
  /// when one is due.
  void publish(const CycleReport& report, const Drivetrain& drivetrain,
               const Hardware& hardware) noexcept;

 private:
  SnapshotBuffer<StateSnapshot> snapshot_;
  RunSampleStage run_samples_;
  StateSnapshot state_{};
};

}  // namespace swivel::rt
