// SPDX-License-Identifier: Apache-2.0
// CalibrationStage: a procedure handed over off the loop is taken at a cycle boundary, drives
// the setpoints until it finishes, fails or is cancelled, and is handed back with how it
// ended; one taken while a fault is latched is refused. Either way the command seen before
// no longer moves the robot.

#include "swivel/rt/calibration_stage.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace swivel::rt {
namespace {

// Drives both wheels at 2 rad/s for `cycles` steps, then finishes.
class StepCalibration final : public Calibration {
 public:
  void configure(const PluginContext& /*ctx*/) override {}
  Status step(const HardwareState& /*readings*/, ActuatorCommand& out) override {
    out = ActuatorCommand{};
    out.module_count = 2;
    if (fail_now) return Status::kError;
    out.wheel_rate_radps = {2.0, 2.0};
    if (++steps >= cycles) done = true;
    return Status::kOk;
  }
  [[nodiscard]] CalibrationProgress progress() const noexcept override { return {}; }
  [[nodiscard]] bool finished() const noexcept override { return done; }
  [[nodiscard]] bool failed() const noexcept override { return false; }
  CalibrationReport analyse() override { return {}; }
  [[nodiscard]] const char* last_error() const noexcept override { return "step failed"; }

  int cycles = 3;
  int steps = 0;
  bool done = false;
  bool fail_now = false;
};

CommandLimits limits() {
  CommandLimits l;
  l.stop_linear_deceleration_mps2 = std::numeric_limits<double>::infinity();
  l.stop_angular_deceleration_radps2 = std::numeric_limits<double>::infinity();
  return l;
}

// The stages side by side as the loop holds them; the padding does not matter in a test.
// NOLINTNEXTLINE(clang-analyzer-optin.performance.Padding)
struct Rig {
  RtLog log;
  LoopEvents events{log};
  PluginGuard guard;
  CommandStage command{limits()};
  CalibrationStage stage;
  HardwareState reading;
  ActuatorCommand setpoints;
  double t_s = 1.0;

  bool cycle(bool final_stop = false) {
    t_s += 0.001;
    stage.take_pending(t_s, command.stopping(), command, events);
    return stage.step(t_s, final_stop, reading, 2, setpoints, command, guard, events);
  }
  void command_motion() {
    VelocityCommand c;
    c.twist.vx_mps = 0.3;
    c.received_s = t_s;
    command.push(c);
    command.take_command(t_s, events);
  }
};

TEST(CalibrationStage, RunsFromTheBoundaryUntilFinishedAndIsHandedBack) {
  Rig rig;
  StepCalibration calibration;
  rig.command_motion();
  ASSERT_TRUE(rig.stage.start(&calibration));
  EXPECT_FALSE(rig.stage.start(&calibration));  // one in flight at a time
  EXPECT_TRUE(rig.cycle());
  EXPECT_EQ(rig.stage.active(), &calibration);
  EXPECT_FALSE(rig.command.moving(false));  // the command seen before is dropped
  EXPECT_EQ(rig.setpoints.wheel_rate_radps[0], 2.0);
  EXPECT_TRUE(rig.cycle());
  EXPECT_FALSE(rig.cycle());  // finished this cycle
  EXPECT_EQ(rig.stage.active(), nullptr);
  CalibrationOutcome outcome = CalibrationOutcome::kNone;
  EXPECT_EQ(rig.stage.take_finished(&outcome), &calibration);
  EXPECT_EQ(outcome, CalibrationOutcome::kFinished);
  EXPECT_FALSE(rig.stage.in_flight());
}

TEST(CalibrationStage, AFailedStepLatchesAFaultAndACancelIsTransient) {
  Rig rig;
  StepCalibration calibration;
  ASSERT_TRUE(rig.stage.start(&calibration));
  EXPECT_TRUE(rig.cycle());
  calibration.fail_now = true;
  EXPECT_FALSE(rig.cycle());
  EXPECT_EQ(rig.events.latched(), FaultCode::kCalibrationError);
  EXPECT_STREQ(rig.events.latched_detail().data(), "step failed");
  CalibrationOutcome outcome = CalibrationOutcome::kNone;
  EXPECT_EQ(rig.stage.take_finished(&outcome), &calibration);
  EXPECT_EQ(outcome, CalibrationOutcome::kFailed);

  rig.events.clear_latched(rig.t_s);
  StepCalibration second;
  ASSERT_TRUE(rig.stage.start(&second));
  EXPECT_TRUE(rig.cycle());
  rig.stage.cancel();
  EXPECT_FALSE(rig.cycle());
  EXPECT_EQ(rig.events.transient(), FaultCode::kCalibrationError);
  EXPECT_EQ(rig.stage.take_finished(&outcome), &second);
  EXPECT_EQ(outcome, CalibrationOutcome::kCancelled);
}

TEST(CalibrationStage, RefusedWhileAFaultIsLatchedAndCancelledBeforeItIsTaken) {
  Rig rig;
  StepCalibration calibration;
  rig.events.raise(FaultCode::kHardwareError, rig.t_s, "bus");
  ASSERT_TRUE(rig.stage.start(&calibration));
  EXPECT_FALSE(rig.cycle());
  CalibrationOutcome outcome = CalibrationOutcome::kNone;
  EXPECT_EQ(rig.stage.take_finished(&outcome), &calibration);
  EXPECT_EQ(outcome, CalibrationOutcome::kRefused);
  EXPECT_EQ(calibration.steps, 0);

  ASSERT_TRUE(rig.stage.start(&calibration));
  rig.stage.cancel();  // not taken yet: handed back at once, never called
  EXPECT_EQ(rig.stage.take_finished(&outcome), &calibration);
  EXPECT_EQ(outcome, CalibrationOutcome::kCancelled);
  EXPECT_EQ(calibration.steps, 0);
}

}  // namespace
}  // namespace swivel::rt
