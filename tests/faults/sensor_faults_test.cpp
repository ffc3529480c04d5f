// SPDX-License-Identifier: Apache-2.0
// Rows of docs/faults.md for faulty sensor readings and a misbehaving hardware plugin, on
// sim + differential + raw_eg (and sim + swpc + raw_eg where redundancy matters). Faults
// are injected at run time through the sim plugin's hook, from the next cycle on.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

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
  // `cause`: the fault_detail the snapshot carries, and the log's text in parentheses.
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
  EXPECT_STREQ(hit.fault_detail.data(), cause.c_str());

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
                           std::to_string(hit.fault_count) + "): safe stop (" + cause + ")"),
            std::string::npos)
      << rig.log();

  rig.loop->clear_fault();
  rig.step();
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle) << "only a command sent after the clear moves";
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  EXPECT_EQ(rig.state().fault_detail[0], '\0');
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
  run_latched_row(rig, "nan_wheel", 0.05, FaultCode::kNonFiniteSensor, "non-finite wheel angle", 1);
}

TEST(SensorFaults, NonFiniteGyroStopsUntilCleared) {
  FaultRig rig;
  run_latched_row(rig, "inf_gyro", 0.05, FaultCode::kNonFiniteSensor, "non-finite gyro rate");
}

TEST(SensorFaults, HardwareNotAnsweringStopsUntilCleared) {
  FaultRig rig;
  run_latched_row(rig, "stall", 0.2, FaultCode::kHardwareError, "sim: hardware not answering");
}

TEST(SensorFaults, HardwareReadErrorStopsUntilCleared) {
  FaultRig rig;
  run_latched_row(rig, "read_error", 0.05, FaultCode::kHardwareError, "sim: injected read error");
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

TEST(SensorFaults, OutOfRangeEncoderJumpIsRejectedAndStopsUntilCleared) {
  // The left encoder jumps by 50 rad in one read (counts lost) and stays offset: 50 000 rad/s
  // "measured" against the 20 rad/s wheel limit. The drivetrain rejects that increment, so
  // the estimate does not jump, and the loop stops the robot in the same cycle. The offset
  // that persists is harmless from the next increment on, so a clear resumes.
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const StateSnapshot before = rig.state();
  ASSERT_LT(distance_m(before.estimate.pose, before.truth), 0.002);
  ASSERT_EQ(rig.inject("out_of_range_wheel", 100.0, 0, 50.0), 0);
  rig.drive(kVxMps, 0.0, 0.0, 1);
  const StateSnapshot jump = rig.state();
  EXPECT_EQ(jump.cycle, before.cycle + 1);
  expect_safe_stop(jump, FaultCode::kDrivetrainError);
  EXPECT_STREQ(jump.fault_detail.data(),
               "differential: left wheel rate implausible (encoder jump)");
  EXPECT_EQ(jump.fault_count, before.fault_count + 1);
  // The rejected rate stays visible in the module state.
  EXPECT_NEAR(jump.modules[0].wheel_rate_meas_radps, 50000.0, 100.0);
  EXPECT_LT(distance_m(jump.estimate.pose, jump.truth), 0.002) << "the jump reached the pose";
  EXPECT_NE(rig.log().find("fault drivetrain_error (#1): safe stop (differential: left wheel "
                           "rate implausible (encoder jump))"),
            std::string::npos)
      << rig.log();
  rig.drive(kVxMps, 0.0, 0.0, 100);
  expect_safe_stop(rig.state(), FaultCode::kDrivetrainError);
  EXPECT_EQ(rig.state().fault_count, jump.fault_count) << "one event";

  rig.loop->clear_fault();
  rig.step();
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle);
  EXPECT_EQ(rig.state().fault_detail[0], '\0');
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const StateSnapshot resumed = rig.state();
  EXPECT_EQ(resumed.mode, LoopMode::kVelocity);
  EXPECT_EQ(resumed.fault_count, jump.fault_count);
  EXPECT_LT(distance_m(resumed.estimate.pose, resumed.truth), 0.005);
}

TEST(SensorFaults, OutOfRangeWheelSpikeOnSwpcNamesTheModule) {
  RigOptions options;
  options.robot = "swpc4";
  options.drivetrain = "swpc";
  FaultRig rig(options);
  rig.drive(kVxMps, 0.0, 0.0, 300);
  ASSERT_EQ(rig.inject("out_of_range_wheel", 0.001, 3, 5.0), 0);  // a one-read spike
  rig.drive(kVxMps, 0.0, 0.0, 1);
  const StateSnapshot hit = rig.state();
  expect_safe_stop(hit, FaultCode::kDrivetrainError);
  EXPECT_STREQ(hit.fault_detail.data(), "swpc: module 3 wheel rate implausible (encoder jump)");
  EXPECT_NEAR(hit.modules[3].wheel_rate_meas_radps, 5000.0, 50.0);
}

TEST(SensorFaults, FrozenEncoderOnDifferentialStopsOnTheGyroDisagreement) {
  // The left encoder stops while the robot drives straight: the encoders read a turn of
  // 0.75 rad/s (the right wheel alone) that the gyro does not see. Two wheels give no
  // redundancy (residual 0); the gyro is the referee. The filtered disagreement crosses
  // 0.2 rad/s within ~20 ms and must stay above it for 0.2 s: a stop ~0.22 s after the freeze.
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const StateSnapshot before = rig.state();
  ASSERT_EQ(rig.inject("frozen_encoder", 1.0, 0), 0);
  rig.drive(kVxMps, 0.0, 0.0, 200);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity) << "persistence not reached yet";
  int cycles = 200;
  while (rig.state().mode == LoopMode::kVelocity && cycles < 300) {
    rig.drive(kVxMps, 0.0, 0.0, 1);
    ++cycles;
  }
  const StateSnapshot hit = rig.state();
  EXPECT_GT(cycles, 200);
  EXPECT_LT(cycles, 250);
  expect_safe_stop(hit, FaultCode::kOdometryInconsistent);
  EXPECT_STREQ(hit.fault_detail.data(), "encoder yaw rate disagrees with the gyro");
  EXPECT_EQ(hit.fault_count, before.fault_count + 1);
  EXPECT_EQ(hit.odometry_residual, 0.0);
  EXPECT_NE(rig.log().find("fault odometry_inconsistent (#1): safe stop (encoder yaw rate "
                           "disagrees with the gyro) ["),
            std::string::npos)
      << rig.log();
  // Latched while the encoder stays frozen; standing still, nothing disagrees, so a clear
  // is honoured, and driving on the frozen encoder stops the robot again.
  rig.drive(kVxMps, 0.0, 0.0, 300);
  expect_safe_stop(rig.state(), FaultCode::kOdometryInconsistent);
  EXPECT_EQ(rig.state().fault_count, hit.fault_count);
  rig.loop->clear_fault();
  rig.drive(kVxMps, 0.0, 0.0, 300);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault_count, hit.fault_count + 1);
  // The encoder answers again (the fault lasted 1 s): its angle catches up in one read, a
  // jump the drivetrain rejects as implausible (a new event). Then a clear resumes.
  rig.drive(kVxMps, 0.0, 0.0, 500);
  EXPECT_EQ(rig.state().fault, FaultCode::kDrivetrainError);
  EXPECT_EQ(rig.state().fault_count, hit.fault_count + 2);
  rig.loop->clear_fault();
  rig.drive(kVxMps, 0.0, 0.0, 1000);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.state().fault_count, hit.fault_count + 2) << rig.log();
}

TEST(SensorFaults, FrozenEncoderOnSwpcStopsOnTheResidual) {
  // One caster wheel of four reads 0 m/s against 0.3 m/s: no rigid-body twist explains it and
  // the least-squares residual rises from ~0 to ~0.09 m/s, above its 0.04 m/s limit.
  RigOptions options;
  options.robot = "swpc4";
  options.drivetrain = "swpc";
  FaultRig rig(options);
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const StateSnapshot before = rig.state();
  ASSERT_EQ(before.mode, LoopMode::kVelocity);
  EXPECT_LT(before.odometry_residual, 0.01);
  ASSERT_EQ(rig.inject("frozen_encoder", 1.0, 2), 0);
  rig.drive(kVxMps, 0.0, 0.0, 200);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity) << "persistence not reached yet";
  EXPECT_GT(rig.state().odometry_residual, 0.05);
  rig.drive(kVxMps, 0.0, 0.0, 60);
  const StateSnapshot hit = rig.state();
  expect_safe_stop(hit, FaultCode::kOdometryInconsistent);
  EXPECT_STREQ(hit.fault_detail.data(), "drivetrain odometry residual above its limit");
  EXPECT_EQ(hit.fault_count, before.fault_count + 1);
}

TEST(SensorFaults, OdometryCheckKeepsQuietInNormalDriving) {
  // The runs the thresholds were chosen on (docs/faults.md), sensor noise on: straight,
  // reverse, arcs, turning in place, desaturated huge commands, caster reorientation and
  // crawling on SWPC. No fault, ever.
  struct Run {
    std::string robot, drivetrain;
    std::vector<std::array<double, 4>> plan;  // vx, vy, wz, cycles
  };
  const std::vector<Run> runs = {
      {"docent",
       "differential",
       {{0.3, 0, 0, 1000},
        {0, 0, 0, 300},
        {0, 0, 1.0, 1000},
        {0.5, 0, -0.8, 1000},
        {-0.3, 0, 0, 500},
        {1e9, 0, 1e9, 500},
        {0, 0, -1e9, 500},
        {1e9, 0, 0, 500}}},
      {"swpc4",
       "swpc",
       {{0.3, 0, 0, 1000},
        {0, 0.3, 0, 1000},
        {-0.3, 0, 0, 1000},
        {0, -0.3, 0.5, 1000},
        {0, 0, 1.0, 1000},
        {0.3, 0.3, -0.5, 1000},
        {1e9, -1e9, 1e9, 500},
        {-1e9, 0, 0, 500},
        {0, 1e9, 0, 500},
        {0, 0, 0, 500},
        {0.05, 0, 0, 500},
        {0, 0.05, 0, 500},
        {0.01, 0.01, 0, 500}}},
  };
  for (const Run& run : runs) {
    RigOptions options;
    options.robot = run.robot;
    options.drivetrain = run.drivetrain;
    options.hardware_params = "{}";  // the sim's defaults: gyro noise on, no slip
    FaultRig rig(options);
    for (const auto& step : run.plan) {
      rig.drive(step[0], step[1], step[2], static_cast<int>(step[3]));
      ASSERT_EQ(rig.state().fault_count, 0U)
          << run.robot << " at " << step[0] << " " << step[1] << " " << step[2] << ": "
          << rig.state().fault_detail.data();
    }
  }
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
