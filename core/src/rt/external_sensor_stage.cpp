// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/external_sensor_stage.hpp"

#include "swivel/rt/finite.hpp"

namespace swivel::rt {

void ExternalSensorStage::take_gyro(double now_s, LoopEvents& events) noexcept {
  GyroSample sample;
  pop_at_most(gyro_, sample, kGyroDrainLimit, [&](const GyroSample& g) {
    if (std::isfinite(g.received_s) && std::isfinite(g.wz_radps)) {
      external_gyro_ = g;
      has_external_gyro_ = true;
      gyro_watch_.observe(g.received_s);
    } else {
      events.log(LogLevel::kWarn, LogCode::kMessage, now_s,
                 "non-finite external gyro sample dropped", g.received_s, g.wz_radps);
    }
  });
}

void ExternalSensorStage::replace_gyro(HardwareState& reading, double now_s) const noexcept {
  if (!gyro_watch_.enabled()) return;
  // The configured external gyro replaces the hardware's; a stale one is no reading (the
  // localization falls back as on a gyro dropout while the fault stops the robot).
  const bool fresh = has_external_gyro_ && gyro_watch_.fresh(now_s);
  reading.gyro_valid = fresh;
  reading.gyro_wz_radps = fresh ? external_gyro_.wz_radps : 0.0;
}

void ExternalSensorStage::take_motion_capture(double now_s, bool reading_ok, HardwareState& reading,
                                              LoopEvents& events) noexcept {
  MotionCaptureInput input;
  MotionCaptureSample newest;
  pop_at_most(motion_capture_, input, kMotionCaptureDrainLimit, [&](const MotionCaptureInput& in) {
    const MotionCaptureSample& m = in.sample;
    if (!m.valid) return;
    if (finite(m)) {
      newest = m;
      if (in.source == MotionCaptureSource::kWatched) motion_capture_watch_.observe(m.stamp_s);
    } else {
      events.log(LogLevel::kWarn, LogCode::kMotionCaptureRejected, now_s,
                 "non-finite motion-capture sample dropped", m.stamp_s);
    }
  });
  if (reading_ok && newest.valid && !reading.motion_capture.valid) reading.motion_capture = newest;
}

// A configured source that went silent is a latched fault; it persists (and refuses a clear)
// for as long as the source stays silent. The causes were written off the loop.
void ExternalSensorStage::check(double now_s, LoopEvents& events) noexcept {
  if (const char* stale = gyro_watch_.check(now_s)) {
    events.raise(FaultCode::kSensorStale, now_s, stale, gyro_watch_.age_s(now_s),
                 gyro_watch_.limit_s());
  }
  if (const char* stale = motion_capture_watch_.check(now_s)) {
    events.raise(FaultCode::kSensorStale, now_s, stale, motion_capture_watch_.age_s(now_s),
                 motion_capture_watch_.limit_s());
  }
}

}  // namespace swivel::rt
