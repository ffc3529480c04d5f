// SPDX-License-Identifier: Apache-2.0
#pragma once
// Sensors that reach the loop from outside the hardware plugin (a ROS 2 IMU or motion-capture
// driver over DDS): the gyro sample the loop takes through a lock-free ring, and the
// staleness watch of each configured source. Plain data and arithmetic on the loop's clock
// (CLOCK_MONOTONIC); everything here is real-time safe except validate().

#include <string>
#include <type_traits>

#include "swivel/rt/state_snapshot.hpp"

namespace swivel::rt {

/// One gyro sample from an external IMU, already rotated into the robot (body) frame.
struct GyroSample {
  double received_s = 0.0;  ///< CLOCK_MONOTONIC at reception, s (its age is now - received_s)
  double wz_radps = 0.0;    ///< body-frame yaw rate, rad/s, counter-clockwise positive
};
static_assert(std::is_trivially_copyable_v<GyroSample>);

/// Where a motion-capture sample pushed into the loop came from. Only the watched source
/// (the configured ROS 2 pose topic) is subject to the staleness watch.
enum class MotionCaptureSource : std::uint8_t {
  kSwivelTopic = 0,  ///< swivel_motion_capture (or an in-process producer): not watched
  kWatched = 1,      ///< the configured external source: counts as its newest sample
};

/// The staleness watch of one external source.
struct SensorWatchOptions {
  bool enabled = false;          ///< the source is configured: the loop watches it
  double max_age_s = 0.05;       ///< newest sample older than this: stale
  double startup_grace_s = 2.0;  ///< from the loop's first cycle: no sample yet is not stale
  /// The fault's cause when the newest sample is too old, and when none came within the
  /// grace period; written off the loop (they name the topic), at most 63 characters.
  FaultDetail stale_detail{};
  FaultDetail silent_detail{};
};

/// The external sources the loop takes samples from (LoopOptions::external_sensors).
struct ExternalSensorOptions {
  SensorWatchOptions gyro;  ///< when enabled, the newest sample replaces the reading's gyro
  SensorWatchOptions motion_capture;  ///< the watched motion-capture source
};

/// Not real-time safe. An empty string when `options` is usable, else what is wrong,
/// starting with `what` (e.g. "external gyro: max_age_s must be finite and positive, got 0").
std::string validate(const SensorWatchOptions& options, const char* what);

/// Loop-side staleness of one source. Loop thread only; real-time safe.
class SensorWatch {
 public:
  SensorWatch() noexcept = default;
  explicit SensorWatch(const SensorWatchOptions& options) noexcept : options_(options) {}

  /// A sample received at `received_s` reached the loop.
  void observe(double received_s) noexcept {
    if (!has_sample_ || received_s > newest_s_) newest_s_ = received_s;
    has_sample_ = true;
  }

  /// The fault's cause when the source is stale at `now_s`, nullptr when it is fresh, still
  /// in its start-up grace, or not configured. The first call starts the grace period.
  [[nodiscard]] const char* check(double now_s) noexcept {
    if (!options_.enabled) return nullptr;
    if (!started_) {
      started_ = true;
      start_s_ = now_s;
    }
    if (!has_sample_) {
      return now_s - start_s_ > options_.startup_grace_s ? options_.silent_detail.data() : nullptr;
    }
    return now_s - newest_s_ > options_.max_age_s ? options_.stale_detail.data() : nullptr;
  }

  /// True when the newest sample is within max_age_s at `now_s` (no sample: false).
  [[nodiscard]] bool fresh(double now_s) const noexcept {
    return has_sample_ && now_s - newest_s_ <= options_.max_age_s;
  }

  /// Age of the newest sample at `now_s`, s; since the start when there is none.
  [[nodiscard]] double age_s(double now_s) const noexcept {
    return now_s - (has_sample_ ? newest_s_ : start_s_);
  }

  /// The limit age_s() is held against: max_age_s, or the grace before the first sample.
  [[nodiscard]] double limit_s() const noexcept {
    return has_sample_ ? options_.max_age_s : options_.startup_grace_s;
  }

  [[nodiscard]] bool enabled() const noexcept { return options_.enabled; }
  [[nodiscard]] const SensorWatchOptions& options() const noexcept { return options_; }

 private:
  SensorWatchOptions options_{};
  bool started_ = false;
  double start_s_ = 0.0;
  bool has_sample_ = false;
  double newest_s_ = 0.0;
};

}  // namespace swivel::rt
