// SPDX-License-Identifier: Apache-2.0
// External sensors on the loop, driven by run_cycle() on synthetic time with the fake
// plugins: the staleness watch, the configured gyro replacing the hardware's, a source never
// heard faulting after its grace, and the watched motion capture reaching the localization.
// The fault rows on the real plugins (stale, clear refused, recovery) are in
// tests/faults/external_sensor_faults_test.cpp.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "fake_plugins.hpp"
#include "swivel/rt/control_loop.hpp"
#include "swivel/rt/rt_log.hpp"  // copy_text

namespace swivel::rt {
namespace {

using test::FakeDrivetrain;
using test::FakeHardware;
using test::FakeLocalization;

constexpr double kDtS = 0.001;

SensorWatchOptions watch(double max_age_s, double grace_s, const char* name) {
  SensorWatchOptions w;
  w.enabled = true;
  w.max_age_s = max_age_s;
  w.startup_grace_s = grace_s;
  copy_text((std::string(name) + ": stale").c_str(), w.stale_detail);
  copy_text((std::string(name) + ": silent").c_str(), w.silent_detail);
  return w;
}

LoopOptions options_with(const ExternalSensorOptions& sensors) {
  LoopOptions o;
  o.realtime = false;
  o.command_timeout_s = 0.5;
  // The external gyro here is not the fake robot's motion: the encoder/gyro check would
  // (rightly) object to the disagreement, which is not what these tests are about.
  o.odometry_check.enabled = false;
  o.external_sensors = sensors;
  return o;
}

class Rig {
 public:
  explicit Rig(const ExternalSensorOptions& sensors)
      : loop(std::make_unique<ControlLoop>(options_with(sensors), hardware, drivetrain,
                                           localization, "fake")) {}

  void step(int cycles = 1) {
    for (int i = 0; i < cycles; ++i) {
      t_s += kDtS;
      loop->run_cycle(t_s);
    }
  }
  // Cycles with a command every 10 ms and, when `gyro` is set, a gyro sample every 5 ms.
  void drive(int cycles, const double* gyro_radps = nullptr) {
    for (int i = 0; i < cycles; ++i) {
      if (i % 10 == 0) {
        VelocityCommand c;
        c.twist = {0.3, 0.0, 0.0};
        c.received_s = t_s;
        c.sequence = ++sequence;
        loop->push_command(c);
      }
      if (gyro_radps != nullptr && i % 5 == 0) {
        ASSERT_TRUE(loop->push_gyro({t_s, *gyro_radps}));
      }
      step();
    }
  }
  [[nodiscard]] StateSnapshot state() const { return loop->latest(); }
  [[nodiscard]] bool wheels_stopped() const {
    return hardware.last_left_radps.load() == 0.0 && hardware.last_right_radps.load() == 0.0;
  }

  FakeHardware hardware;
  FakeDrivetrain drivetrain;
  FakeLocalization localization;
  std::unique_ptr<ControlLoop> loop;
  double t_s = 50.0;
  std::uint64_t sequence = 0;
};

TEST(SensorWatch, StaleAfterMaxAgeAndSilentAfterTheGrace) {
  SensorWatch w(watch(0.05, 1.0, "rt/imu"));
  EXPECT_EQ(w.check(10.0), nullptr);  // starts the grace
  EXPECT_EQ(w.check(11.0), nullptr);  // at its end: not yet
  ASSERT_NE(w.check(11.001), nullptr);
  EXPECT_EQ(w.limit_s(), 1.0);  // the grace, before the first sample
  EXPECT_STREQ(w.check(11.001), "rt/imu: silent");
  w.observe(11.0);
  EXPECT_EQ(w.check(11.049), nullptr);
  EXPECT_STREQ(w.check(11.0501), "rt/imu: stale");
  w.observe(10.0);  // an older sample does not make it fresh
  EXPECT_STREQ(w.check(11.0501), "rt/imu: stale");
  EXPECT_NEAR(w.age_s(11.0501), 0.0501, 1e-12);
  EXPECT_EQ(w.limit_s(), 0.05);
  SensorWatch off;
  EXPECT_EQ(off.check(1e9), nullptr);
}

TEST(ExternalSensors, InvalidOptionsAreRefusedNamingTheSource) {
  FakeHardware hw;
  FakeDrivetrain dt;
  FakeLocalization loc;
  ExternalSensorOptions sensors;
  sensors.gyro = watch(0.0, 1.0, "rt/imu");
  try {
    ControlLoop loop(options_with(sensors), hw, dt, loc, "fake");
    FAIL() << "a zero max age was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "external gyro: max_age_s must be finite and positive, got 0.000000");
  }
  sensors.gyro = watch(0.05, 1.0, "rt/imu");
  sensors.motion_capture = watch(0.1, -1.0, "rt/pose");
  EXPECT_THROW(ControlLoop(options_with(sensors), hw, dt, loc, "fake"), std::invalid_argument);
}

TEST(ExternalSensors, TheNewestGyroSampleReplacesTheHardwareReading) {
  ExternalSensorOptions sensors;
  sensors.gyro = watch(0.05, 1.0, "rt/imu");
  Rig rig(sensors);
  rig.step(5);
  // Within the grace and without a sample: no gyro (the localization falls back), no fault.
  EXPECT_EQ(rig.state().gyro_wz_radps, 0.0);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  ASSERT_TRUE(rig.loop->push_gyro({rig.t_s, 0.25}));
  ASSERT_TRUE(rig.loop->push_gyro({rig.t_s, 0.75}));  // the newest of a cycle wins
  rig.step();
  EXPECT_EQ(rig.state().gyro_wz_radps, 0.75);
  const double gyro = -0.4;
  rig.drive(200, &gyro);
  EXPECT_EQ(rig.state().gyro_wz_radps, -0.4);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.state().fault_count, 0U);
  // A non-finite sample is dropped: the previous one holds.
  ASSERT_TRUE(rig.loop->push_gyro({rig.t_s, std::numeric_limits<double>::quiet_NaN()}));
  rig.step();
  EXPECT_EQ(rig.state().gyro_wz_radps, -0.4);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
}

TEST(ExternalSensors, WithoutTheSourceConfiguredTheHardwareGyroStays) {
  Rig rig(ExternalSensorOptions{});
  rig.drive(100);
  ASSERT_TRUE(rig.loop->push_gyro({rig.t_s, 5.0}));
  rig.step();
  EXPECT_NE(rig.state().gyro_wz_radps, 5.0);
  rig.step(5000);  // nothing configured: nothing goes stale
  EXPECT_EQ(rig.state().fault, FaultCode::kCommandTimeout);  // only the commands stopped
}

TEST(ExternalSensors, ASourceNeverHeardFaultsAfterTheGracePeriod) {
  ExternalSensorOptions sensors;
  sensors.motion_capture = watch(0.1, 0.5, "rt/mocap/pose");
  Rig rig(sensors);
  rig.drive(500);  // 0.5 s: the grace
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  rig.drive(2);
  EXPECT_EQ(rig.state().fault, FaultCode::kSensorStale);
  EXPECT_STREQ(rig.state().fault_detail.data(), "rt/mocap/pose: silent");
  EXPECT_TRUE(rig.wheels_stopped());
}

TEST(ExternalSensors, WatchedMotionCaptureReachesTheLocalizationAndKeepsItFresh) {
  ExternalSensorOptions sensors;
  sensors.motion_capture = watch(0.1, 0.5, "rt/mocap/pose");
  Rig rig(sensors);
  for (int i = 0; i < 2000; ++i) {
    if (i % 10 == 0) {
      MotionCaptureSample m;
      m.valid = true;
      m.stamp_s = rig.t_s;
      m.pose = {1.5 + 0.001 * i, -0.25, 0.3};
      ASSERT_TRUE(rig.loop->push_motion_capture(m, MotionCaptureSource::kWatched));
    }
    rig.drive(1);
  }
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  EXPECT_NEAR(rig.localization.last_motion_capture_x_m.load(), 1.5 + 1.99, 1e-9);
  // The Swivel topic's samples reach the localization too, but do not keep the watched
  // source fresh.
  for (int i = 0; i < 200; ++i) {
    MotionCaptureSample m;
    m.valid = true;
    m.stamp_s = rig.t_s;
    m.pose = {7.0, 0.0, 0.0};
    ASSERT_TRUE(rig.loop->push_motion_capture(m));
    rig.drive(1);
  }
  EXPECT_EQ(rig.localization.last_motion_capture_x_m.load(), 7.0);
  EXPECT_EQ(rig.state().fault, FaultCode::kSensorStale);
  EXPECT_STREQ(rig.state().fault_detail.data(), "rt/mocap/pose: stale");
}

}  // namespace
}  // namespace swivel::rt
