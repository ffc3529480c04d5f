// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's stage for sensors from outside the hardware plugin (LoopOptions::external_sensors:
// a DDS gyro, motion capture from DDS). Samples cross from the external-sensor thread through
// two SPSC rings; each cycle the loop drains at most one ring's worth of each (a source
// pushing as fast as the loop drains cannot hold the cycle), keeps the newest finite sample,
// lets a configured gyro replace the hardware reading's and motion capture fill in where the
// reading has none, and raises kSensorStale for a configured source that went silent.
//
// One external-sensor thread calls push_*() (single producer); everything else runs on the
// loop thread. Real-time safe: no allocation, no lock, no I/O; noexcept.

#include <cstddef>

#include "swivel/rt/external_sensors.hpp"
#include "swivel/rt/loop_events.hpp"
#include "swivel/rt/spsc_ring.hpp"
#include "swivel/types.hpp"

namespace swivel::rt {

class ExternalSensorStage {
 public:
  /// The options must be valid (validate()).
  explicit ExternalSensorStage(const ExternalSensorOptions& options) noexcept
      : gyro_watch_(options.gyro), motion_capture_watch_(options.motion_capture) {}

  /// The external-sensor thread. False (dropped) when the ring is full.
  bool push_motion_capture(const MotionCaptureSample& sample, MotionCaptureSource source) noexcept {
    return motion_capture_.try_push({sample, source});
  }
  /// The external-sensor thread. False (dropped) when the ring is full.
  bool push_gyro(const GyroSample& sample) noexcept { return gyro_.try_push(sample); }

  /// Loop thread, before the hardware read: the newest finite gyro sample (a non-finite one
  /// is dropped and logged).
  void take_gyro(double now_s, LoopEvents& events) noexcept;

  /// Loop thread, on a successful read: with a configured gyro its newest sample replaces the
  /// reading's rate; a stale one is no reading (gyro_valid false).
  void replace_gyro(HardwareState& reading, double now_s) const noexcept;

  /// Loop thread, after the read: the newest finite motion-capture sample (a non-finite one is
  /// dropped and logged); it becomes the reading's when `reading_ok` and the reading has none.
  void take_motion_capture(double now_s, bool reading_ok, HardwareState& reading,
                           LoopEvents& events) noexcept;

  /// Loop thread: kSensorStale for each configured source that is stale at `now_s`.
  void check(double now_s, LoopEvents& events) noexcept;

 private:
  struct MotionCaptureInput {
    MotionCaptureSample sample;
    MotionCaptureSource source = MotionCaptureSource::kSwivelTopic;
  };
  SpscRing<MotionCaptureInput, 64> motion_capture_;
  SpscRing<GyroSample, 64> gyro_;
  /// Samples taken per cycle at most: a ring's capacity.
  static constexpr std::size_t kMotionCaptureDrainLimit = decltype(motion_capture_)::capacity();
  static constexpr std::size_t kGyroDrainLimit = decltype(gyro_)::capacity();

  GyroSample external_gyro_{};  // newest finite external gyro sample
  bool has_external_gyro_ = false;
  SensorWatch gyro_watch_;
  SensorWatch motion_capture_watch_;
};

}  // namespace swivel::rt
