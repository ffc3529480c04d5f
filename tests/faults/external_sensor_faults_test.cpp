// SPDX-License-Identifier: Apache-2.0
// Rows of docs/faults.md for external sensors (a ROS 2 IMU or motion-capture topic over
// DDS), on sim + differential + raw_eg: the gyro comes from outside the hardware through the
// loop's ring, as the DDS subscriber pushes it, here on the rig's synthetic clock. A source
// that stops, or never starts, latches sensor_stale naming the topic and stops the robot; a
// clear is refused while the source stays silent and honoured once it is back.

#include <gtest/gtest.h>

#include <string>

#include "fault_rig.hpp"
#include "swivel/rt/rt_log.hpp"  // copy_text

namespace swivel::faults {
namespace {

constexpr double kVxMps = 0.3;

rt::SensorWatchOptions watch(double max_age_s, double grace_s, const char* stale,
                             const char* silent) {
  rt::SensorWatchOptions w;
  w.enabled = true;
  w.max_age_s = max_age_s;
  w.startup_grace_s = grace_s;
  rt::copy_text(stale, w.stale_detail);
  rt::copy_text(silent, w.silent_detail);
  return w;
}

RigOptions imu_rig() {
  RigOptions o;
  // The rig's sim has no sensor noise; its gyro is replaced by the external one.
  o.localization_params = "{heading_source: gyro}";
  o.external_sensors.gyro = watch(0.05, 1.0, "rt/imu: no IMU sample for over 0.05 s",
                                  "rt/imu: no IMU sample within 1 s of start");
  return o;
}

// Straight driving with a command every 10 ms and, while `imu` is true, a gyro sample of
// 0 rad/s (the truth on a straight line) every 5 ms, stamped on the rig's clock.
void drive(FaultRig& rig, int cycles, bool imu) {
  for (int i = 0; i < cycles; ++i) {
    if (i % 10 == 0) rig.command(kVxMps, 0.0, 0.0);
    if (imu && i % 5 == 0) {
      ASSERT_TRUE(rig.loop->push_gyro({rig.t_s, 0.0}));
    }
    rig.step();
  }
}

void expect_safe_stop(const StateSnapshot& s, const char* cause) {
  EXPECT_EQ(s.mode, LoopMode::kSafeStop);
  EXPECT_EQ(s.fault, FaultCode::kSensorStale) << fault_code_name(s.fault);
  EXPECT_STREQ(s.fault_detail.data(), cause);
  EXPECT_EQ(max_wheel_setpoint(s), 0.0);
  EXPECT_EQ(s.command_twist.vx_mps, 0.0);
}

TEST(ExternalSensorFaults, ImuThatStopsSafeStopsNamingTheTopicUntilItIsBack) {
  FaultRig rig(imu_rig());
  drive(rig, 500, true);
  const StateSnapshot before = rig.state();
  ASSERT_EQ(before.mode, LoopMode::kVelocity);
  ASSERT_GT(max_wheel_setpoint(before), 1.0);
  // The last sample went in before the cycle of i = 495, five cycles ago.
  const double last_sample_s = rig.t_s - 0.005;

  // The IMU publisher stops; commands keep coming.
  int cycles = 0;
  while (rig.state().fault == FaultCode::kNone && cycles < 200) {
    drive(rig, 1, false);
    ++cycles;
  }
  const StateSnapshot hit = rig.state();
  expect_safe_stop(hit, "rt/imu: no IMU sample for over 0.05 s");
  // The first cycle past the max age.
  EXPECT_GT(hit.stamp_s - last_sample_s, 0.05);
  EXPECT_LE(hit.stamp_s - last_sample_s, 0.0511);
  EXPECT_EQ(hit.fault_count, before.fault_count + 1);
  EXPECT_NE(rig.log().find("fault sensor_stale (#1): safe stop (rt/imu: no IMU sample for over "
                           "0.05 s)"),
            std::string::npos)
      << rig.log();

  rig.step();
  const Pose2 stopped = rig.state().truth;
  drive(rig, 300, false);
  expect_safe_stop(rig.state(), "rt/imu: no IMU sample for over 0.05 s");
  EXPECT_EQ(rig.state().fault_count, hit.fault_count) << "a persisting cause is one event";
  EXPECT_LT(distance_m(rig.state().truth, stopped), 1e-12) << "the robot moved in safe stop";

  // A clear is refused while the IMU stays silent ...
  rig.loop->request_clear(1);
  rig.step();
  rt::LoopReply reply;
  ASSERT_TRUE(rig.loop->take_reply(reply));
  EXPECT_FALSE(reply.ok);
  EXPECT_EQ(reply.fault, FaultCode::kSensorStale);
  EXPECT_STREQ(reply.detail.data(), "rt/imu: no IMU sample for over 0.05 s");

  // ... and honoured once it is back; a fresh command then moves the robot.
  drive(rig, 20, true);
  rig.loop->request_clear(2);
  drive(rig, 1, true);
  ASSERT_TRUE(rig.loop->take_reply(reply));
  EXPECT_TRUE(reply.ok);
  drive(rig, 300, true);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  EXPECT_GT(distance_m(rig.state().truth, stopped), 0.05);
}

TEST(ExternalSensorFaults, ImuNeverHeardFaultsAfterTheStartUpGrace) {
  FaultRig rig(imu_rig());
  const double start_s = rig.t_s + FaultRig::kDtS;  // the first cycle starts the grace
  int cycles = 0;
  while (rig.state().fault == FaultCode::kNone && cycles < 2000) {
    drive(rig, 1, false);
    ++cycles;
  }
  // Driving without a gyro until the grace (1 s) is over, then stopped.
  EXPECT_GT(rig.state().stamp_s - start_s, 1.0);
  EXPECT_LE(rig.state().stamp_s - start_s, 1.0011);
  expect_safe_stop(rig.state(), "rt/imu: no IMU sample within 1 s of start");
}

TEST(ExternalSensorFaults, MotionCapturePoseThatStopsSafeStops) {
  RigOptions o;
  o.external_sensors.motion_capture =
      watch(0.1, 1.0, "rt/mocap/docent/pose: no pose sample for over 0.1 s",
            "rt/mocap/docent/pose: no pose sample within 1 s of start");
  FaultRig rig(o);
  for (int i = 0; i < 500; ++i) {
    if (i % 10 == 0) {
      rig.command(kVxMps, 0.0, 0.0);
      MotionCaptureSample m;
      m.valid = true;
      m.stamp_s = rig.t_s;
      m.pose = rig.state().truth;
      ASSERT_TRUE(rig.loop->push_motion_capture(m, rt::MotionCaptureSource::kWatched));
    }
    rig.step();
  }
  ASSERT_EQ(rig.state().mode, LoopMode::kVelocity);
  // The last pose went in before the cycle of i = 490: 0.01 s ago.
  rig.drive(kVxMps, 0.0, 0.0, 85);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);  // 0.095 s: within the max age
  rig.drive(kVxMps, 0.0, 0.0, 10);
  expect_safe_stop(rig.state(), "rt/mocap/docent/pose: no pose sample for over 0.1 s");
}

}  // namespace
}  // namespace swivel::faults
