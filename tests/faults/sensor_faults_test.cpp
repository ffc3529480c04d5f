// Rows of docs/faults.md for faulty sensor readings and a misbehaving hardware plugin, on
// sim + differential + raw_eg (and sim + swpc + raw_eg where redundancy matters). Faults
// are injected at run time through the sim plugin's hook, from the next cycle on.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "fault_rig.hpp"

namespace swivel::faults {
namespace {

constexpr double kVxMps = 0.3;

// The loop has stopped the robot in a controlled way this cycle: safe stop with `code`,
// zero twist applied and zero wheel setpoints.
void expect_safe_stop(const StateSnapshot& s, FaultCode code) {
  EXPECT_EQ(s.mode, LoopMode::kSafeStop);
  EXPECT_EQ(s.fault, code) << fault_code_name(s.fault);
  EXPECT_EQ(max_wheel_setpoint(s), 0.0);
  EXPECT_EQ(max_steer_setpoint(s), 0.0);
  EXPECT_EQ(s.command_twist.vx_mps, 0.0);
  EXPECT_EQ(s.command_twist.wz_radps, 0.0);
}

// A latched sensor / hardware fault, end to end: driving, the fault from the next cycle for
// `duration_s`, a stop in that very cycle, one counted event, the world standing still from
// the cycle after (the zero setpoints reached the hardware), no recovery without
// clear_fault() even with fresh commands, and recovery after it.
void run_latched_row(FaultRig& rig, const char* kind, double duration_s, FaultCode code,
                     const std::string& cause, unsigned module = 0) {
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const StateSnapshot before = rig.state();
  ASSERT_EQ(before.mode, LoopMode::kVelocity);
  ASSERT_GT(max_wheel_setpoint(before), 1.0);

  ASSERT_EQ(rig.inject(kind, duration_s, module), 0);
  rig.command(kVxMps, 0.0, 0.0);
  rig.step();
  const StateSnapshot hit = rig.state();
  EXPECT_EQ(hit.cycle, before.cycle + 1);
  expect_safe_stop(hit, code);
  EXPECT_EQ(hit.fault_count, before.fault_count + 1);

  rig.step();
  const Pose2 stopped = rig.state().truth;
  // Fresh commands keep arriving while the fault lasts and after it cleared.
  const int fault_cycles = static_cast<int>(std::lround(duration_s / FaultRig::kDtS));
  rig.drive(kVxMps, 0.0, 0.0, fault_cycles + 200);
  const StateSnapshot latched = rig.state();
  EXPECT_EQ(latched.cycle, hit.cycle + 1 + static_cast<std::uint64_t>(fault_cycles + 200));
  expect_safe_stop(latched, code);
  EXPECT_EQ(latched.fault_count, hit.fault_count) << "a persisting cause is one event";
  EXPECT_LT(distance_m(latched.truth, stopped), 1e-12) << "the robot moved in safe stop";
  EXPECT_NE(rig.log().find("fault " + std::string(fault_code_name(code)) + " (#" +
                           std::to_string(hit.fault_count) + "): safe stop" + cause),
            std::string::npos)
      << rig.log();

  rig.loop->clear_fault();
  rig.step();
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle) << "only a command sent after the clear moves";
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  rig.drive(kVxMps, 0.0, 0.0, 100);
  const StateSnapshot resumed = rig.state();
  EXPECT_EQ(resumed.mode, LoopMode::kVelocity);
  EXPECT_EQ(resumed.fault, FaultCode::kNone);
  EXPECT_NEAR(resumed.command_twist.vx_mps, kVxMps, 1e-12);
  EXPECT_GT(distance_m(resumed.truth, stopped), 0.02);
  EXPECT_EQ(resumed.fault_count, hit.fault_count);
}

TEST(SensorFaults, NonFiniteWheelAngleStopsUntilCleared) {
  FaultRig rig;
  run_latched_row(rig, "nan_wheel", 0.05, FaultCode::kNonFiniteSensor, "", 1);
}

TEST(SensorFaults, NonFiniteGyroStopsUntilCleared) {
  FaultRig rig;
  run_latched_row(rig, "inf_gyro", 0.05, FaultCode::kNonFiniteSensor, "");
}

TEST(SensorFaults, HardwareNotAnsweringStopsUntilCleared) {
  FaultRig rig;
  run_latched_row(rig, "stall", 0.2, FaultCode::kHardwareError, " (sim: hardware not answering)");
}

TEST(SensorFaults, HardwareReadErrorStopsUntilCleared) {
  FaultRig rig;
  run_latched_row(rig, "read_error", 0.05, FaultCode::kHardwareError,
                  " (sim: injected read error)");
}

TEST(SensorFaults, ClearRequestedDuringAStallWaitsForTheFirstAnsweredRead) {
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 100);
  ASSERT_EQ(rig.inject("stall", 0.05), 0);
  rig.step(10);
  rig.loop->clear_fault();
  rig.step(35);  // 45 of the 50 silent cycles
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  rig.step(10);
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  EXPECT_EQ(rig.state().fault_count, 1U);
}

TEST(SensorFaults, ScheduledStallFromParamsStopsTheLoadedPlugin) {
  // The `faults:` schedule, through the plugin as the daemon configures it. Sim time counts
  // from the first read (the first cycle).
  RigOptions options;
  options.hardware_params =
      "{sensor_noise: false, motion_capture: false,"
      " faults: [{kind: stall, start_s: 0.3005, duration_s: 0.1}]}";
  FaultRig rig(options);
  rig.drive(kVxMps, 0.0, 0.0, 301);  // sim time 0 .. 0.300
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  rig.drive(kVxMps, 0.0, 0.0, 1);
  expect_safe_stop(rig.state(), FaultCode::kHardwareError);
  rig.drive(kVxMps, 0.0, 0.0, 200);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault_count, 1U);
}

TEST(SensorFaults, WriteErrorStopsButTheHardwareKeepsItsLastSetpoints) {
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 300);
  ASSERT_EQ(rig.inject("write_error", 0.05), 0);
  rig.step();
  // The failure shows at the end of the cycle (the write): safe stop from that cycle, zero
  // setpoints from the next one.
  const StateSnapshot hit = rig.state();
  EXPECT_EQ(hit.mode, LoopMode::kSafeStop);
  EXPECT_EQ(hit.fault, FaultCode::kHardwareError);
  EXPECT_EQ(hit.fault_count, 1U);
  rig.step();
  expect_safe_stop(rig.state(), FaultCode::kHardwareError);
  // The zero setpoints are refused too: the world moves on at the last accepted ones.
  const Pose2 at_hit = rig.state().truth;
  rig.step(40);
  EXPECT_NEAR(distance_m(rig.state().truth, at_hit), kVxMps * 0.040, 1e-3);
  // The first write after the fault lands the zeros.
  rig.step(20);
  const Pose2 after = rig.state().truth;
  rig.step(50);
  EXPECT_LT(distance_m(rig.state().truth, after), 1e-12);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault_count, 1U);
  EXPECT_NE(rig.log().find("fault hardware_error (#1): safe stop (sim: injected write error)"),
            std::string::npos);
  rig.loop->clear_fault();
  rig.drive(kVxMps, 0.0, 0.0, 50);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
}

TEST(SensorFaults, OutOfRangeEncoderJumpIsNotDetected) {
  // A persistent jump of 50 rad on the left encoder (counts lost) during one read. The loop
  // takes that cycle's odometry at face value: no fault, the estimate jumps.
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const StateSnapshot before = rig.state();
  ASSERT_LT(distance_m(before.estimate.pose, before.truth), 0.002);
  ASSERT_EQ(rig.inject("out_of_range_wheel", 100.0, 0, 50.0), 0);
  rig.drive(kVxMps, 0.0, 0.0, 1);
  const StateSnapshot jump = rig.state();
  EXPECT_EQ(jump.mode, LoopMode::kVelocity);
  EXPECT_EQ(jump.fault, FaultCode::kNone);
  EXPECT_EQ(jump.fault_count, before.fault_count);
  // 50 rad in 1 ms: 50000 rad/s "measured", 2500 times the drivetrain's 20 rad/s limit.
  EXPECT_NEAR(jump.modules[0].wheel_rate_meas_radps, 50000.0, 100.0);
  EXPECT_GT(distance_m(jump.estimate.pose, jump.truth), 0.2);
  rig.drive(kVxMps, 0.0, 0.0, 100);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.state().fault_count, before.fault_count);
}

TEST(SensorFaults, FrozenEncoderOnDifferentialIsNotDetected) {
  // The left encoder stops while the robot drives straight: the odometry sees half the
  // distance (and a turn the gyro does not confirm); two wheels give no redundancy
  // (residual stays 0), so nothing is raised.
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const StateSnapshot before = rig.state();
  ASSERT_EQ(rig.inject("frozen_encoder", 1.0, 0), 0);
  rig.drive(kVxMps, 0.0, 0.0, 500);
  const StateSnapshot frozen = rig.state();
  EXPECT_EQ(frozen.mode, LoopMode::kVelocity);
  EXPECT_EQ(frozen.fault, FaultCode::kNone);
  EXPECT_EQ(frozen.fault_count, before.fault_count);
  EXPECT_EQ(frozen.odometry_residual, 0.0);
  EXPECT_EQ(frozen.modules[0].wheel_rate_meas_radps, 0.0);
  const double travelled_m = distance_m(frozen.truth, before.truth);
  EXPECT_NEAR(travelled_m, kVxMps * 0.5, 0.002);
  EXPECT_NEAR(distance_m(frozen.estimate.pose, before.estimate.pose), travelled_m / 2.0, 0.005);
  EXPECT_GT(distance_m(frozen.estimate.pose, frozen.truth), 0.05);
}

TEST(SensorFaults, FrozenEncoderOnSwpcRaisesTheResidualButNoFault) {
  RigOptions options;
  options.robot = "swpc4";
  options.drivetrain = "swpc";
  FaultRig rig(options);
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const StateSnapshot before = rig.state();
  ASSERT_EQ(before.mode, LoopMode::kVelocity);
  ASSERT_EQ(rig.inject("frozen_encoder", 1.0, 2), 0);
  rig.drive(kVxMps, 0.0, 0.0, 200);
  const StateSnapshot frozen = rig.state();
  EXPECT_EQ(frozen.mode, LoopMode::kVelocity);
  EXPECT_EQ(frozen.fault, FaultCode::kNone);
  EXPECT_EQ(frozen.fault_count, before.fault_count);
  // One wheel of four reads 0 m/s against 0.3 m/s: the least-squares fit cannot explain it.
  EXPECT_LT(before.odometry_residual, 0.01);
  EXPECT_GT(frozen.odometry_residual, 0.05);
  EXPECT_GT(frozen.odometry_residual, 10.0 * before.odometry_residual);
}

TEST(SensorFaults, GyroDropoutFallsBackToEncoderHeading) {
  // The world's gyro reads 0.05 rad/s too high (an effect the nominal model does not know):
  // the gyro-based heading of raw_eg turns 10 % faster than the encoders say while the
  // gyro is valid, and exactly as the encoders say while it drops out. No fault either way.
  RigOptions options;
  options.world_effects["gyro_bias"]["bias_rad_s"] = 0.05;
  FaultRig rig(options);
  constexpr double kWzRadps = 0.5;
  auto yaw_rate = [&](int cycles) {
    const double start = rig.state().estimate.pose.yaw_rad;
    rig.drive(0.0, 0.0, kWzRadps, cycles);
    return std::remainder(rig.state().estimate.pose.yaw_rad - start, 2.0 * M_PI) /
           (cycles * FaultRig::kDtS);
  };
  rig.drive(0.0, 0.0, kWzRadps, 100);  // up to speed
  EXPECT_NEAR(yaw_rate(1000), kWzRadps + 0.05, 0.005);
  ASSERT_EQ(rig.inject("gyro_dropout", 1.0), 0);
  EXPECT_NEAR(yaw_rate(1000), kWzRadps, 0.005);
  EXPECT_EQ(rig.state().gyro_wz_radps, 0.0);
  EXPECT_NEAR(yaw_rate(1000), kWzRadps + 0.05, 0.005);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.state().fault_count, 0U);
}

}  // namespace
}  // namespace swivel::faults
