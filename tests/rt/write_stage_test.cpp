// SPDX-License-Identifier: Apache-2.0
// WriteStage: the limited twist through the drivetrain's inverse kinematics to the hardware;
// zero setpoints without a basis, after a calibration, on a refused or non-finite inverse;
// a failed write is a hardware fault, reported to the hardware once until a clear.

#include "swivel/rt/write_stage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "fake_plugins.hpp"

namespace swivel::rt {
namespace {

using test::FakeDrivetrain;

constexpr double kPeriodS = 0.001;

/// Refuses or fails to write on demand.
class FailingHardware final : public Hardware {
 public:
  bool fail_write = false;
  bool throw_on_write = false;
  int on_errors = 0;
  std::string last_cause;
  void configure(const PluginContext& /*ctx*/) override {}
  void on_error(const char* cause) override {
    ++on_errors;
    last_cause = cause;
  }
  Status read(double /*stamp_s*/, HardwareState& /*out*/) override { return Status::kOk; }
  Status write(const ActuatorCommand& /*command*/) override {
    if (throw_on_write) throw std::runtime_error("bus frame 7 lost: CRC mismatch");
    return fail_write ? Status::kError : Status::kOk;
  }
  [[nodiscard]] const char* last_error() const noexcept override { return "bus write failed"; }
};

/// Gives non-finite setpoints.
class NanDrivetrain final : public Drivetrain {
 public:
  void configure(const PluginContext& /*ctx*/) override {}
  [[nodiscard]] std::uint32_t module_count() const noexcept override { return 2; }
  Status forward(const HardwareState& /*previous*/, const HardwareState& /*current*/,
                 OdometryIncrement& /*out*/) override {
    return Status::kOk;
  }
  Status inverse(const Twist2& requested, const HardwareState& /*basis*/, double /*dt_s*/,
                 ActuatorCommand& out, Twist2& applied) override {
    out = ActuatorCommand{};
    out.module_count = 2;
    out.wheel_rate_radps[0] = std::numeric_limits<double>::quiet_NaN();
    applied = requested;
    return Status::kOk;
  }
  void module_states(std::span<ModuleState> /*out*/) const noexcept override {}
};

CommandLimits no_limits() {
  CommandLimits l;
  l.stop_linear_deceleration_mps2 = std::numeric_limits<double>::infinity();
  l.stop_angular_deceleration_radps2 = std::numeric_limits<double>::infinity();
  l.period_s = kPeriodS;
  return l;
}

// The stage with its neighbours, as the loop holds them; the padding does not matter here.
// NOLINTNEXTLINE(clang-analyzer-optin.performance.Padding)
struct Rig {
  RtLog log;
  LoopEvents events{log};
  PluginGuard guard;
  CommandStage command{no_limits()};
  WriteStage stage{2, kPeriodS};
  FailingHardware hardware;
  FakeDrivetrain drivetrain;
  HardwareState reading;
  const char* failure = nullptr;

  Twist2 write(const WriteRequest& request, Drivetrain& kinematics) {
    failure = nullptr;
    return stage.write(request, CycleTime{1.0, true, 1.0 - kPeriodS}, kinematics, hardware, command,
                       guard, events, failure);
  }
  Twist2 write(const WriteRequest& request) { return write(request, drivetrain); }
};

WriteRequest moving_at(const HardwareState& basis, double vx_mps) {
  WriteRequest r;
  r.basis = &basis;
  r.target = {vx_mps, 0.0, 0.0};
  r.moving = true;
  return r;
}

TEST(WriteStage, TheTwistGoesThroughTheInverseKinematicsToTheHardware) {
  Rig rig;
  rig.reading.module_count = 2;
  const Twist2 applied = rig.write(moving_at(rig.reading, 0.5));
  EXPECT_EQ(applied.vx_mps, 0.5);
  EXPECT_NEAR(rig.stage.setpoints().wheel_rate_radps[0], 5.0, 1e-12);  // 0.5 m/s, 0.1 m wheel
  EXPECT_FALSE(rig.stage.last_write_zero());
  EXPECT_EQ(rig.failure, nullptr);

  WriteRequest final_cycle = moving_at(rig.reading, 0.5);
  final_cycle.final_stop = true;  // zero at once
  EXPECT_EQ(rig.write(final_cycle).vx_mps, 0.0);
  EXPECT_TRUE(rig.stage.last_write_zero());
}

TEST(WriteStage, ZeroSetpointsWithoutABasisOrAfterACalibration) {
  Rig rig;
  WriteRequest none;
  none.target = {0.5, 0.0, 0.0};
  none.moving = true;
  EXPECT_EQ(rig.write(none).vx_mps, 0.0);
  EXPECT_TRUE(rig.stage.last_write_zero());
  EXPECT_EQ(rig.stage.setpoints().module_count, 2U);
  EXPECT_EQ(rig.events.fault_count(), 0U);

  rig.stage.setpoints().wheel_rate_radps[0] = 2.0;  // a calibration's setpoints
  WriteRequest calibrating;
  calibrating.basis = &rig.reading;
  calibrating.calibrating = true;
  (void)rig.write(calibrating);
  EXPECT_FALSE(rig.stage.last_write_zero());  // written as the procedure gave them
  WriteRequest ended = moving_at(rig.reading, 0.5);
  ended.calibration_ended = true;
  EXPECT_EQ(rig.write(ended).vx_mps, 0.0);
  EXPECT_TRUE(rig.stage.last_write_zero());
}

TEST(WriteStage, ANonFiniteInverseIsADrivetrainFaultWithZeroSetpoints) {
  Rig rig;
  NanDrivetrain nan_drivetrain;
  EXPECT_EQ(rig.write(moving_at(rig.reading, 0.5), nan_drivetrain).vx_mps, 0.0);
  EXPECT_EQ(rig.events.latched(), FaultCode::kDrivetrainError);
  EXPECT_STREQ(rig.events.latched_detail().data(), "non-finite setpoints");
  EXPECT_TRUE(rig.stage.last_write_zero());
}

TEST(WriteStage, AFailedWriteIsReportedToTheHardwareOnceUntilAClear) {
  Rig rig;
  rig.hardware.fail_write = true;
  (void)rig.write(moving_at(rig.reading, 0.0));
  ASSERT_NE(rig.failure, nullptr);
  EXPECT_STREQ(rig.failure, "bus write failed");
  EXPECT_EQ(rig.events.latched(), FaultCode::kHardwareError);
  rig.stage.report_hardware_failure(rig.failure, 1.0, rig.hardware, rig.guard, rig.events);
  (void)rig.write(moving_at(rig.reading, 0.0));
  rig.stage.report_hardware_failure(rig.failure, 1.0, rig.hardware, rig.guard, rig.events);
  EXPECT_EQ(rig.hardware.on_errors, 1);
  EXPECT_TRUE(rig.stage.hardware_in_error());
  rig.stage.clear_hardware_error();
  rig.stage.report_hardware_failure(rig.failure, 1.0, rig.hardware, rig.guard, rig.events);
  EXPECT_EQ(rig.hardware.on_errors, 2);
  rig.stage.report_hardware_failure(nullptr, 1.0, rig.hardware, rig.guard, rig.events);
  EXPECT_EQ(rig.hardware.on_errors, 2);
}

// What a plugin threw lives in the guard's buffer, which the guarded on_error() call reuses:
// the hardware must still be told the whole cause, and the log must carry it.
TEST(WriteStage, AThrownWriteReachesOnErrorWhole) {
  Rig rig;
  rig.hardware.throw_on_write = true;
  (void)rig.write(moving_at(rig.reading, 0.0));
  ASSERT_NE(rig.failure, nullptr);
  const std::string expected = "plugin threw std::runtime_error: bus frame 7 lost: CRC mismatch";
  EXPECT_EQ(std::string(rig.failure), expected);
  rig.stage.report_hardware_failure(rig.failure, 1.0, rig.hardware, rig.guard, rig.events);
  EXPECT_EQ(rig.hardware.on_errors, 1);
  EXPECT_EQ(rig.hardware.last_cause, expected);
}

}  // namespace
}  // namespace swivel::rt
