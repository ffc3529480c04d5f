// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/hardware_read_stage.hpp"

#include "swivel/rt/finite.hpp"

namespace swivel::rt {

const char* non_finite_field(const HardwareState& s) noexcept {
  if (!finite(s.stamp_s)) return "non-finite reading timestamp";
  for (std::uint32_t i = 0; i < s.module_count; ++i) {
    if (!finite(s.wheel_angle_rad[i])) return "non-finite wheel angle";
    if (!finite(s.steer_angle_rad[i])) return "non-finite steering angle";
  }
  if (s.gyro_valid && !finite(s.gyro_wz_radps)) return "non-finite gyro rate";
  if (s.motion_capture.valid &&
      (!finite(s.motion_capture.stamp_s) || !finite(s.motion_capture.pose))) {
    return "non-finite motion-capture sample in the reading";
  }
  return nullptr;
}

ReadOutcome HardwareReadStage::read(double now_s, Hardware& hardware, ExternalSensorStage& sensors,
                                    PluginGuard& guard, LoopEvents& events) noexcept {
  ReadOutcome outcome;
  const char* thrown = nullptr;
  sensors.take_gyro(now_s, events);
  if (guard([&] { return hardware.read(now_s, current_); }, thrown) != Status::kOk) {
    outcome.failure = thrown != nullptr ? thrown : hardware.last_error();
    events.raise(FaultCode::kHardwareError, now_s, outcome.failure);
  } else if (current_.module_count > kMaxModules) {
    outcome.failure = "module count out of range";
    events.raise(FaultCode::kHardwareError, now_s, outcome.failure);
  } else {
    sensors.replace_gyro(current_, now_s);
    if (const char* field = non_finite_field(current_); field != nullptr) {
      events.raise(FaultCode::kNonFiniteSensor, now_s, field);
    } else {
      outcome.ok = true;
    }
  }
  sensors.take_motion_capture(now_s, outcome.ok, current_, events);
  sensors.check(now_s, events);
  return outcome;
}

}  // namespace swivel::rt
