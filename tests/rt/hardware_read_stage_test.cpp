// SPDX-License-Identifier: Apache-2.0
// HardwareReadStage and ExternalSensorStage: a reading reaches the loop's later stages only
// when it is usable; a failed, throwing, oversized or non-finite read raises its fault; the
// external gyro and motion capture are taken around the read. With them LoopEvents (faults
// counted once per event) and PluginGuard (a throwing plugin becomes kError with its text).

#include "swivel/rt/hardware_read_stage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace swivel::rt {
namespace {

/// A hardware whose read() fills in what the test sets, or fails or throws.
class ScriptedHardware final : public Hardware {
 public:
  HardwareState next;
  bool fail = false;
  bool throw_ = false;

  void configure(const PluginContext& /*ctx*/) override {}
  Status read(double stamp_s, HardwareState& out) override {
    if (throw_) throw std::runtime_error("bus gone");
    if (fail) return Status::kError;
    out = next;
    out.stamp_s = stamp_s;
    return Status::kOk;
  }
  Status write(const ActuatorCommand& /*command*/) override { return Status::kOk; }
  [[nodiscard]] const char* last_error() const noexcept override { return "read timed out"; }
};

SensorWatchOptions watch(double max_age_s, double grace_s) {
  SensorWatchOptions w;
  w.enabled = true;
  w.max_age_s = max_age_s;
  w.startup_grace_s = grace_s;
  copy_text("gyro: stale", w.stale_detail);
  copy_text("gyro: silent", w.silent_detail);
  return w;
}

// The stages side by side as the loop holds them; the padding does not matter in a test.
// NOLINTNEXTLINE(clang-analyzer-optin.performance.Padding)
struct Rig {
  RtLog log;
  LoopEvents events{log};
  PluginGuard guard;
  ExternalSensorOptions options;
  ExternalSensorStage sensors{options};
  HardwareReadStage stage;
  ScriptedHardware hardware;

  Rig() { hardware.next.module_count = 2; }
  ReadOutcome read(double now_s) {
    events.begin_cycle(0);
    return stage.read(now_s, hardware, sensors, guard, events);
  }
};

TEST(HardwareReadStage, AUsableReadingBecomesThePreviousAtTheCycleEnd) {
  Rig rig;
  rig.hardware.next.wheel_angle_rad[0] = 1.5;
  const ReadOutcome first = rig.read(1.0);
  EXPECT_TRUE(first.ok);
  EXPECT_EQ(first.failure, nullptr);
  EXPECT_EQ(rig.stage.current().wheel_angle_rad[0], 1.5);
  EXPECT_FALSE(rig.stage.has_previous());
  rig.stage.end_cycle(first.ok);
  ASSERT_TRUE(rig.stage.has_previous());
  EXPECT_EQ(rig.stage.previous().stamp_s, 1.0);
  rig.stage.forget_previous();
  EXPECT_FALSE(rig.stage.has_previous());
  EXPECT_EQ(rig.events.fault_count(), 0U);
}

TEST(HardwareReadStage, AFailedOrThrowingReadIsAHardwareFaultWithItsCause) {
  Rig rig;
  rig.hardware.fail = true;
  ReadOutcome out = rig.read(1.0);
  EXPECT_FALSE(out.ok);
  ASSERT_NE(out.failure, nullptr);
  EXPECT_STREQ(out.failure, "read timed out");
  EXPECT_EQ(rig.events.latched(), FaultCode::kHardwareError);
  EXPECT_EQ(rig.events.cycle_fault(), FaultCode::kHardwareError);
  rig.stage.end_cycle(out.ok);
  EXPECT_FALSE(rig.stage.has_previous());

  out = rig.read(1.001);  // the same cause persisting is one event
  EXPECT_EQ(rig.events.fault_count(), 1U);

  rig.hardware.fail = false;
  rig.hardware.throw_ = true;
  out = rig.read(1.002);
  EXPECT_FALSE(out.ok);
  ASSERT_NE(out.failure, nullptr);
  EXPECT_EQ(std::string(out.failure), "plugin threw std::runtime_error: bus gone");
}

TEST(HardwareReadStage, TooManyModulesOrANonFiniteValueIsNoReading) {
  Rig rig;
  rig.hardware.next.module_count = kMaxModules + 1;
  ReadOutcome out = rig.read(1.0);
  EXPECT_FALSE(out.ok);
  EXPECT_STREQ(out.failure, "module count out of range");

  rig.events.clear_latched(1.0);
  rig.hardware.next.module_count = 2;
  rig.hardware.next.steer_angle_rad[1] = std::nan("");
  out = rig.read(1.001);
  EXPECT_FALSE(out.ok);
  EXPECT_EQ(out.failure, nullptr);  // not the hardware's failure: no on_error()
  EXPECT_EQ(rig.events.latched(), FaultCode::kNonFiniteSensor);
  EXPECT_STREQ(rig.events.latched_detail().data(), "non-finite steering angle");
}

TEST(HardwareReadStage, NonFiniteFieldNamesTheFirstOne) {
  HardwareState s;
  s.module_count = 1;
  EXPECT_EQ(non_finite_field(s), nullptr);
  s.gyro_wz_radps = std::nan("");
  EXPECT_EQ(non_finite_field(s), nullptr);  // not valid: not read
  s.gyro_valid = true;
  EXPECT_STREQ(non_finite_field(s), "non-finite gyro rate");
  s.wheel_angle_rad[0] = INFINITY;
  EXPECT_STREQ(non_finite_field(s), "non-finite wheel angle");
  s.stamp_s = std::nan("");
  EXPECT_STREQ(non_finite_field(s), "non-finite reading timestamp");
  HardwareState m;
  m.motion_capture.valid = true;
  m.motion_capture.pose.yaw_rad = std::nan("");
  EXPECT_STREQ(non_finite_field(m), "non-finite motion-capture sample in the reading");
}

TEST(ExternalSensorStage, AConfiguredGyroReplacesTheReadingsAndGoesStale) {
  Rig rig;
  rig.options.gyro = watch(0.05, 1.0);
  ExternalSensorStage sensors(rig.options);
  rig.hardware.next.gyro_valid = true;
  rig.hardware.next.gyro_wz_radps = 9.0;
  ASSERT_TRUE(sensors.push_gyro({0.995, 0.25}));
  ASSERT_TRUE(sensors.push_gyro({0.996, std::nan("")}));  // dropped
  rig.events.begin_cycle(0);
  ReadOutcome out = rig.stage.read(1.0, rig.hardware, sensors, rig.guard, rig.events);
  ASSERT_TRUE(out.ok);
  EXPECT_TRUE(rig.stage.current().gyro_valid);
  EXPECT_EQ(rig.stage.current().gyro_wz_radps, 0.25);

  rig.events.begin_cycle(1);
  out = rig.stage.read(1.1, rig.hardware, sensors, rig.guard, rig.events);
  EXPECT_TRUE(out.ok);  // a stale gyro is no reading, and a latched fault
  EXPECT_FALSE(rig.stage.current().gyro_valid);
  EXPECT_EQ(rig.stage.current().gyro_wz_radps, 0.0);
  EXPECT_EQ(rig.events.latched(), FaultCode::kSensorStale);
  EXPECT_STREQ(rig.events.latched_detail().data(), "gyro: stale");
}

TEST(ExternalSensorStage, MotionCaptureFillsInOnlyWhereTheReadingHasNone) {
  Rig rig;
  MotionCaptureSample m;
  m.valid = true;
  m.stamp_s = 0.99;
  m.pose = {1.0, 2.0, 0.5};
  ASSERT_TRUE(rig.sensors.push_motion_capture(m, MotionCaptureSource::kSwivelTopic));
  ASSERT_TRUE(rig.read(1.0).ok);
  EXPECT_TRUE(rig.stage.current().motion_capture.valid);
  EXPECT_EQ(rig.stage.current().motion_capture.pose.y_m, 2.0);

  rig.hardware.next.motion_capture.valid = true;
  rig.hardware.next.motion_capture.pose = {7.0, 0.0, 0.0};
  ASSERT_TRUE(rig.sensors.push_motion_capture(m, MotionCaptureSource::kSwivelTopic));
  ASSERT_TRUE(rig.read(1.001).ok);
  EXPECT_EQ(rig.stage.current().motion_capture.pose.x_m, 7.0);  // the hardware's own

  rig.hardware.fail = true;
  m.pose.x_m = std::nan("");
  ASSERT_TRUE(rig.sensors.push_motion_capture(m, MotionCaptureSource::kSwivelTopic));
  EXPECT_FALSE(rig.read(1.002).ok);  // drained and dropped all the same
  EXPECT_EQ(rig.events.latched(), FaultCode::kHardwareError);
}

TEST(LoopEvents, TransientFaultsAndTheSnapshotsMode) {
  RtLog log;
  LoopEvents events(log);
  events.begin_cycle(3);
  events.raise_transient(FaultCode::kCommandTimeout, 1.0, "velocity command timed out");
  events.raise_transient(FaultCode::kCommandTimeout, 1.1, "velocity command timed out");
  EXPECT_EQ(events.fault_count(), 1U);  // a timeout is one event until a command arrives
  events.raise_transient(FaultCode::kNonFiniteCommand, 1.2, "rejected");
  events.raise_transient(FaultCode::kNonFiniteCommand, 1.3, "rejected");
  EXPECT_EQ(events.fault_count(), 3U);  // every rejected command is one
  StateSnapshot state;
  events.publish(LoopMode::kVelocity, state);
  EXPECT_EQ(state.mode, LoopMode::kVelocity);
  EXPECT_EQ(state.fault, FaultCode::kNonFiniteCommand);
  EXPECT_STREQ(state.fault_detail.data(), "rejected");
  EXPECT_EQ(state.fault_count, 3U);

  events.raise(FaultCode::kDrivetrainError, 1.4, "");  // no reason: the code's name
  events.publish(LoopMode::kVelocity, state);
  EXPECT_EQ(state.mode, LoopMode::kSafeStop);
  EXPECT_STREQ(state.fault_detail.data(), "drivetrain_error");
  events.clear_latched(1.5);
  events.clear_transient();
  events.publish(LoopMode::kIdle, state);
  EXPECT_EQ(state.mode, LoopMode::kIdle);
  EXPECT_EQ(state.fault, FaultCode::kNone);
  EXPECT_EQ(state.fault_detail[0], '\0');
  EXPECT_EQ(events.cycle_fault(), FaultCode::kDrivetrainError);
  events.begin_cycle(4);
  EXPECT_EQ(events.cycle_fault(), FaultCode::kNone);
}

TEST(PluginGuard, AnythingThrownBecomesAnErrorWithItsText) {
  PluginGuard guard;
  const char* thrown = "stale";
  EXPECT_EQ(guard([] { return Status::kOk; }, thrown), Status::kOk);
  EXPECT_EQ(thrown, nullptr);
  EXPECT_EQ(guard([]() -> Status { throw 42; }, thrown), Status::kError);
  ASSERT_NE(thrown, nullptr);
  EXPECT_EQ(std::string(thrown), "plugin threw int (not a std::exception)");
}

}  // namespace
}  // namespace swivel::rt
