// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/control_loop.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "fake_plugins.hpp"

namespace swivel::rt {
namespace {

using test::FakeDrivetrain;
using test::FakeHardware;
using test::FakeLocalization;
using test::kFakeWheelRadiusM;

constexpr double kDtS = 0.001;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

LoopOptions test_options() {
  LoopOptions o;
  o.rate_hz = 1000.0;
  o.realtime = false;
  o.command_timeout_s = 0.5;
  return o;
}

// Drives the loop with run_cycle() on synthetic time: deterministic, no threads.
class LoopRig {
 public:
  explicit LoopRig(const LoopOptions& options = test_options())
      : loop(std::make_unique<ControlLoop>(options, hardware, drivetrain, localization, "fake_a")) {
  }

  void command(double vx_mps, double wz_radps) {
    VelocityCommand c;
    c.twist = {vx_mps, 0.0, wz_radps};
    c.received_s = t_s;
    c.sequence = ++sequence;
    ASSERT_TRUE(loop->push_command(c));
  }
  void step(int cycles = 1) {
    for (int i = 0; i < cycles; ++i) {
      t_s += kDtS;
      loop->run_cycle(t_s);
    }
  }
  // Cycles with a fresh command every 10 ms, as a 100 Hz command source would send.
  void drive(double vx_mps, double wz_radps, int cycles) {
    for (int i = 0; i < cycles; ++i) {
      if (i % 10 == 0) command(vx_mps, wz_radps);
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
  double t_s = 100.0;
  std::uint64_t sequence = 0;
};

double planar_distance(const Pose2& a, const Pose2& b) {
  return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m);
}

TEST(ControlLoop, RejectsNonPositiveRate) {
  FakeHardware hw;
  FakeDrivetrain dt;
  FakeLocalization loc;
  LoopOptions o = test_options();
  o.rate_hz = 0.0;
  try {
    ControlLoop loop(o, hw, dt, loc, "fake");
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rate_hz must be finite and positive"), std::string::npos)
        << e.what();
  }
}

TEST(ControlLoop, StartsIdleWithoutCommand) {
  LoopRig rig;
  rig.step(5);
  const StateSnapshot s = rig.state();
  EXPECT_EQ(s.cycle, 5U);
  EXPECT_EQ(s.mode, LoopMode::kIdle);
  EXPECT_EQ(s.fault, FaultCode::kNone);
  EXPECT_TRUE(rig.wheels_stopped());
  EXPECT_STREQ(s.localization_plugin.data(), "fake_a");
  EXPECT_EQ(s.module_count, 2U);
}

TEST(ControlLoop, FollowsCommandAndEstimatesPose) {
  LoopRig rig;
  rig.drive(0.5, 0.0, 200);
  const StateSnapshot s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kVelocity);
  EXPECT_EQ(s.fault, FaultCode::kNone);
  EXPECT_DOUBLE_EQ(s.command_twist.vx_mps, 0.5);
  EXPECT_DOUBLE_EQ(rig.hardware.last_left_radps.load(), 0.5 / kFakeWheelRadiusM);
  // The first cycle only writes the setpoint; 199 cycles of motion follow it.
  EXPECT_NEAR(s.estimate.pose.x_m, 0.5 * 0.199, 1e-9);
  ASSERT_TRUE(s.has_truth);
  EXPECT_NEAR(planar_distance(s.estimate.pose, s.truth), 0.0, 1e-9);
  EXPECT_NEAR(s.odometry_twist.vx_mps, 0.5, 1e-9);
  EXPECT_NEAR(s.modules[0].wheel_rate_cmd_radps, 5.0, 1e-12);
}

TEST(ControlLoop, CommandTimeoutStopsRobotAndReportsFault) {
  LoopRig rig;
  rig.command(0.4, 0.2);
  rig.step(499);  // newest command 0.499 s old: still valid
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_FALSE(rig.wheels_stopped());

  rig.step(2);  // 0.501 s old
  StateSnapshot s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kIdle);
  EXPECT_EQ(s.fault, FaultCode::kCommandTimeout);
  EXPECT_EQ(s.fault_count, 1U);
  EXPECT_EQ(s.command_twist.vx_mps, 0.0);
  EXPECT_EQ(s.command_twist.wz_radps, 0.0);
  EXPECT_TRUE(rig.wheels_stopped());

  rig.step(100);  // a persisting timeout is one fault event
  EXPECT_EQ(rig.state().fault_count, 1U);

  rig.command(0.1, 0.0);
  rig.step();
  s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kVelocity);
  EXPECT_EQ(s.fault, FaultCode::kNone);
  EXPECT_DOUBLE_EQ(s.command_twist.vx_mps, 0.1);
}

TEST(ControlLoop, NonFiniteCommandIsRejectedAndStopsRobot) {
  LoopRig rig;
  rig.drive(0.3, 0.0, 20);
  VelocityCommand bad;
  bad.twist = {kNaN, 0.0, 0.0};
  bad.received_s = rig.t_s;
  ASSERT_TRUE(rig.loop->push_command(bad));
  rig.step();
  StateSnapshot s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kIdle);
  EXPECT_EQ(s.fault, FaultCode::kNonFiniteCommand);
  EXPECT_EQ(s.fault_count, 1U);
  EXPECT_TRUE(rig.wheels_stopped());
  EXPECT_TRUE(std::isfinite(rig.hardware.last_left_radps.load()));

  rig.command(0.2, 0.0);
  rig.step();
  s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kVelocity);
  EXPECT_EQ(s.fault, FaultCode::kNone);
}

TEST(ControlLoop, NonFiniteSensorSafeStopsWithinOneCycle) {
  LoopRig rig;
  rig.drive(0.5, 0.3, 100);
  const Pose2 before = rig.state().estimate.pose;
  rig.hardware.inject_nan = true;
  rig.command(0.5, 0.3);
  rig.step();
  StateSnapshot s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kSafeStop);
  EXPECT_EQ(s.fault, FaultCode::kNonFiniteSensor);
  EXPECT_EQ(s.fault_count, 1U);
  EXPECT_TRUE(rig.wheels_stopped());
  EXPECT_EQ(s.command_twist.vx_mps, 0.0);
  // The bad reading never reached the localization; what is published meanwhile is dead
  // reckoning over the cycle at the last measured twist.
  EXPECT_NEAR(planar_distance(rig.localization.estimate().pose, before), 0.0, 1e-12);
  EXPECT_TRUE(std::isfinite(s.estimate.pose.x_m));
  EXPECT_NEAR(planar_distance(s.estimate.pose, before), 0.5 * kDtS, 1e-9);

  rig.drive(0.5, 0.3, 50);  // the fault persists: one event, still stopped
  EXPECT_EQ(rig.state().fault_count, 1U);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_TRUE(rig.wheels_stopped());

  rig.hardware.inject_nan = false;  // cause gone, but nobody cleared: stays stopped
  rig.drive(0.5, 0.3, 50);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault, FaultCode::kNonFiniteSensor);
  EXPECT_TRUE(rig.wheels_stopped());
}

TEST(ControlLoop, PluginErrorSafeStopsUntilClearedAndHealthy) {
  LoopRig rig;
  rig.drive(0.3, 0.0, 50);
  rig.localization.fail_update = true;
  rig.drive(0.3, 0.0, 10);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault, FaultCode::kLocalizationError);
  EXPECT_TRUE(rig.wheels_stopped());

  rig.loop->clear_fault();  // requested while the plugin still fails: must wait
  rig.drive(0.3, 0.0, 10);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_TRUE(rig.wheels_stopped());

  rig.localization.fail_update = false;
  rig.step();  // the pending request is honoured in the first healthy cycle
  StateSnapshot s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kIdle);  // commands from before the clear are discarded
  EXPECT_EQ(s.fault, FaultCode::kNone);
  EXPECT_EQ(s.fault_count, 1U);
  EXPECT_TRUE(rig.wheels_stopped());

  rig.command(0.3, 0.0);
  rig.step();
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_FALSE(rig.wheels_stopped());
}

// A NaN in the covariance stops the robot like a NaN pose, and never reaches a subscriber
// (robot_localization and Nav2 reject it): the published estimate carries no covariance.
TEST(ControlLoop, NonFiniteCovarianceSafeStopsAndIsNotPublished) {
  LoopRig rig;
  rig.drive(0.3, 0.0, 50);
  rig.localization.nan_covariance = true;
  rig.drive(0.3, 0.0, 2);
  const StateSnapshot s = rig.state();
  EXPECT_EQ(s.mode, LoopMode::kSafeStop);
  EXPECT_EQ(s.fault, FaultCode::kLocalizationError);
  EXPECT_STREQ(s.fault_detail.data(), "non-finite pose covariance");
  EXPECT_TRUE(rig.wheels_stopped());
  EXPECT_FALSE(s.estimate.has_covariance);
  for (const double v : s.estimate.covariance) EXPECT_TRUE(std::isfinite(v));
}

TEST(ControlLoop, ThrowingPluginSafeStopsInsteadOfTerminating) {
  LoopRig rig;
  rig.drive(0.3, 0.0, 50);
  rig.localization.throw_in_update = true;
  rig.drive(0.3, 0.0, 5);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault, FaultCode::kLocalizationError);
  EXPECT_TRUE(rig.wheels_stopped());

  rig.localization.throw_in_update = false;
  rig.loop->clear_fault();
  rig.step();
  rig.command(0.3, 0.0);
  rig.step();
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
}

TEST(ControlLoop, DrivetrainAndHardwareErrorsSafeStop) {
  LoopRig rig;
  rig.drive(0.3, 0.0, 20);
  rig.drivetrain.fail_forward = true;
  rig.drive(0.3, 0.0, 1);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault, FaultCode::kDrivetrainError);
  EXPECT_TRUE(rig.wheels_stopped());
  rig.drivetrain.fail_forward = false;

  rig.hardware.fail_read = true;
  const auto writes = rig.hardware.writes.load();
  rig.drive(0.3, 0.0, 1);
  EXPECT_EQ(rig.state().fault, FaultCode::kHardwareError);
  EXPECT_EQ(rig.state().fault_count, 2U);
  EXPECT_EQ(rig.hardware.writes.load(), writes + 1);  // zero setpoints still written
  EXPECT_TRUE(rig.wheels_stopped());
}

TEST(ControlLoop, ClearRequestedWhileHealthyDoesNotClearALaterFault) {
  LoopRig rig;
  rig.drive(0.3, 0.0, 10);
  rig.loop->clear_fault();
  rig.step();
  rig.hardware.inject_nan = true;
  rig.step();
  rig.hardware.inject_nan = false;
  rig.drive(0.3, 0.0, 20);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault, FaultCode::kNonFiniteSensor);
}

TEST(ControlLoop, HotSwapKeepsPoseContinuousAndCountsSwap) {
  LoopRig rig;
  FakeLocalization next;
  next.reset(PoseEstimate{Pose2{5.0, -3.0, 1.0}, {}, false});  // deliberately elsewhere
  rig.drive(0.5, 0.4, 300);
  const StateSnapshot before = rig.state();
  const auto old_updates = rig.localization.updates.load();

  ASSERT_TRUE(rig.loop->request_localization_swap(&next, "fake_b"));
  EXPECT_TRUE(rig.loop->swap_pending());
  EXPECT_FALSE(rig.loop->request_localization_swap(&rig.localization, "fake_a"));  // pending
  rig.drive(0.5, 0.4, 1);
  const StateSnapshot after = rig.state();

  EXPECT_EQ(after.localization_swaps, 1U);
  EXPECT_STREQ(after.localization_plugin.data(), "fake_b");
  EXPECT_EQ(next.hand_overs.load(), 1U);
  EXPECT_EQ(rig.loop->active_localization(), &next);
  EXPECT_FALSE(rig.loop->swap_pending());
  // One cycle at 0.5 m/s moves 0.5 mm: anything more is a jump.
  EXPECT_LE(planar_distance(after.estimate.pose, before.estimate.pose), 0.5 * kDtS + 1e-9);
  EXPECT_NEAR(after.estimate.pose.yaw_rad, before.estimate.pose.yaw_rad, 0.4 * kDtS + 1e-9);
  EXPECT_NEAR(planar_distance(after.estimate.pose, after.truth), 0.0, 1e-9);

  // The old instance is released exactly once and never called again.
  EXPECT_FALSE(rig.loop->request_localization_swap(&rig.localization, "fake_a"));  // not taken
  EXPECT_EQ(rig.loop->take_retired_localization(), &rig.localization);
  EXPECT_EQ(rig.loop->take_retired_localization(), nullptr);
  rig.drive(0.5, 0.4, 100);
  EXPECT_EQ(rig.localization.updates.load(), old_updates);
  EXPECT_NEAR(planar_distance(rig.state().estimate.pose, rig.state().truth), 0.0, 1e-9);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
}

TEST(ControlLoop, HandsMotionCaptureToLocalization) {
  LoopRig rig;
  MotionCaptureSample sample;
  sample.valid = true;
  sample.stamp_s = rig.t_s;
  sample.pose = {1.25, 0.0, 0.0};
  rig.step();
  ASSERT_TRUE(rig.loop->push_motion_capture(sample));
  rig.step();
  EXPECT_DOUBLE_EQ(rig.localization.last_motion_capture_x_m.load(), 1.25);

  sample.pose.x_m = kNaN;  // dropped, not a stop
  ASSERT_TRUE(rig.loop->push_motion_capture(sample));
  rig.step();
  EXPECT_DOUBLE_EQ(rig.localization.last_motion_capture_x_m.load(), 1.25);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
}

TEST(ControlLoop, HandsOutEveryNthCycleAsARunSample) {
  LoopOptions o = test_options();
  o.run_sample_rate_hz = 100.0;  // every 10th cycle at 1 kHz
  LoopRig rig(o);
  EXPECT_DOUBLE_EQ(rig.loop->run_sample_period_s(), 0.01);
  rig.drive(0.5, 0.0, 200);
  std::vector<RunSample> samples;
  RunSample r;
  while (rig.loop->take_run_sample(r)) samples.push_back(r);
  ASSERT_EQ(samples.size(), 20U);  // cycles 1, 11, ..., 191
  for (std::size_t k = 0; k < samples.size(); ++k) {
    EXPECT_EQ(samples[k].sequence, k + 1);
    EXPECT_EQ(samples[k].cycle, 10 * k + 1);  // from the first cycle on, every 10 ms
  }
  rig.step();  // cycle 201: due
  ASSERT_TRUE(rig.loop->take_run_sample(r));
  EXPECT_EQ(r.cycle, 201U);
  rig.step(9);  // not due again before cycle 211
  EXPECT_FALSE(rig.loop->take_run_sample(r));
  rig.step();
  ASSERT_TRUE(rig.loop->take_run_sample(r));
  EXPECT_EQ(r.cycle, 211U);
  samples.push_back(r);
  const RunSample& last = samples.back();
  const StateSnapshot s = rig.state();  // the last sample's cycle
  EXPECT_EQ(last.stamp_s, s.stamp_s);
  EXPECT_EQ(last.command_twist.vx_mps, 0.5);
  EXPECT_EQ(last.module_count, 2U);
  EXPECT_EQ(last.wheel_angle_rad[0], s.wheel_angle_rad[0]);
  EXPECT_GT(last.wheel_angle_rad[0], samples.front().wheel_angle_rad[0]);
  EXPECT_EQ(last.estimate.x_m, s.estimate.pose.x_m);
  ASSERT_TRUE(last.has_truth);  // the fake hardware reports its true pose
  EXPECT_EQ(last.truth.x_m, s.truth.x_m);
  EXPECT_EQ(last.truth_stamp_s, s.stamp_s);
  EXPECT_EQ(last.fault, FaultCode::kNone);
  EXPECT_EQ(last.mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.loop->run_samples_dropped(), 0U);
}

TEST(ControlLoop, RunSamplesKeepTheirRateWhenCyclesAreLateOrSkipped) {
  LoopOptions o = test_options();
  o.run_sample_rate_hz = 100.0;
  LoopRig rig(o);
  // Wake-up jitter of a third of a period either way, and a skipped deadline now and then
  // (the loop skips the cycles it missed): still one sample per 10 ms.
  const double t0 = rig.t_s;
  std::vector<double> stamps;
  RunSample r;
  for (int k = 1; k <= 2000; ++k) {
    if (k % 97 == 0) continue;  // a skipped deadline
    const double jitter_s = (k % 3 == 0 ? 0.3 : (k % 3 == 1 ? -0.3 : 0.0)) * kDtS;
    rig.loop->run_cycle(t0 + k * kDtS + jitter_s);
    while (rig.loop->take_run_sample(r)) stamps.push_back(r.stamp_s);
  }
  ASSERT_EQ(stamps.size(), 200U);
  for (std::size_t k = 1; k < stamps.size(); ++k) {
    // At most a skipped cycle plus the jitter of two wake-ups apart from 10 ms.
    EXPECT_NEAR(stamps[k] - stamps[k - 1], 0.01, 0.0017) << "at sample " << k;
  }
}

TEST(ControlLoop, AFullRunSampleRingDropsAndCountsInsteadOfBlocking) {
  LoopOptions o = test_options();
  o.run_sample_rate_hz = 1000.0;  // every cycle
  LoopRig rig(o);
  const auto capacity = ControlLoop::kRunSampleRingCapacity;
  rig.step(static_cast<int>(capacity) + 30);  // nobody takes them
  EXPECT_EQ(rig.loop->run_samples_dropped(), 30U);
  RunSample r;
  std::uint64_t last = 0;
  while (rig.loop->take_run_sample(r)) last = r.sequence;
  EXPECT_EQ(last, capacity);
  rig.step();
  ASSERT_TRUE(rig.loop->take_run_sample(r));
  EXPECT_EQ(r.sequence, capacity + 31) << "the lost samples show as a jump in the sequence";
}

TEST(ControlLoop, RunSamplesOffByDefaultAndRateChecked) {
  LoopRig rig;
  rig.step(50);
  RunSample r;
  EXPECT_FALSE(rig.loop->take_run_sample(r));
  EXPECT_EQ(rig.loop->run_sample_period_s(), 0.0);
  FakeHardware hw;
  FakeDrivetrain dt;
  FakeLocalization loc;
  for (const double bad : {-1.0, 2000.0, kNaN}) {
    LoopOptions o = test_options();
    o.run_sample_rate_hz = bad;
    EXPECT_THROW(ControlLoop(o, hw, dt, loc, "fake"), std::invalid_argument) << bad;
  }
}

TEST(ControlLoopThread, RunsAndStopsWithZeroSetpoints) {
  FakeHardware hardware;
  FakeDrivetrain drivetrain;
  FakeLocalization localization;
  ControlLoop loop(test_options(), hardware, drivetrain, localization, "fake_a");
  const auto warnings = loop.start();
  EXPECT_TRUE(warnings.empty());  // realtime: false asks for nothing that can be refused
  EXPECT_TRUE(loop.running());
  EXPECT_THROW(loop.start(), std::logic_error);

  // Keep commanding until the loop reports following it (generous deadline: loaded CI).
  std::uint64_t sequence = 0;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < give_up) {
    VelocityCommand c;
    c.twist = {0.2, 0.0, 0.1};
    c.received_s = loop.now_s();
    c.sequence = ++sequence;
    loop.push_command(c);
    const StateSnapshot s = loop.latest();
    if (s.mode == LoopMode::kVelocity && s.cycle > 20) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_EQ(loop.latest().mode, LoopMode::kVelocity);
  EXPECT_NE(hardware.last_left_radps.load(), 0.0);

  loop.stop();
  EXPECT_FALSE(loop.running());
  EXPECT_EQ(hardware.last_left_radps.load(), 0.0);
  EXPECT_EQ(hardware.last_right_radps.load(), 0.0);
  const TimingReport timing = loop.timing();
  EXPECT_GT(timing.cycles, 20U);
  EXPECT_GE(timing.lateness_max_us, timing.lateness_p50_us);
  loop.stop();  // idempotent
  EXPECT_FALSE(loop.running());
}

// A procedure that drives both wheels at 2 rad/s for `cycles` steps, then finishes.
class FakeCalibration final : public Calibration {
 public:
  void configure(const PluginContext&) override {}
  Status step(const HardwareState&, ActuatorCommand& out) noexcept override {
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
  [[nodiscard]] const char* last_error() const noexcept override { return "fake failure"; }

  int cycles = 50;
  int steps = 0;
  bool done = false;
  bool fail_now = false;
};

TEST(ControlLoopCalibration, RunsAtCycleBoundaryIgnoresCommandsAndHandsBack) {
  LoopRig rig;
  FakeCalibration calibration;
  ASSERT_TRUE(rig.loop->start_calibration(&calibration));
  EXPECT_FALSE(rig.loop->start_calibration(&calibration));  // one in flight at a time
  EXPECT_EQ(rig.loop->take_finished_calibration(), nullptr);
  rig.drive(0.5, 0.0, 10);  // commands are ignored while calibrating
  EXPECT_EQ(rig.state().mode, LoopMode::kCalibration);
  EXPECT_EQ(rig.hardware.last_left_radps.load(), 2.0);  // the procedure's setpoints, not IK
  EXPECT_EQ(calibration.steps, 10);

  rig.step(40);
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle);  // the old command does not resume
  EXPECT_TRUE(rig.wheels_stopped());
  CalibrationOutcome outcome = CalibrationOutcome::kNone;
  EXPECT_EQ(rig.loop->take_finished_calibration(&outcome), &calibration);
  EXPECT_EQ(outcome, CalibrationOutcome::kFinished);
  EXPECT_FALSE(rig.loop->calibration_in_flight());
  EXPECT_EQ(calibration.steps, 50);
}

TEST(ControlLoopCalibration, StepErrorSafeStopsWithCalibrationError) {
  LoopRig rig;
  FakeCalibration calibration;
  ASSERT_TRUE(rig.loop->start_calibration(&calibration));
  rig.step(5);
  calibration.fail_now = true;
  rig.step();
  EXPECT_TRUE(rig.wheels_stopped());
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault, FaultCode::kCalibrationError);
  CalibrationOutcome outcome = CalibrationOutcome::kNone;
  EXPECT_EQ(rig.loop->take_finished_calibration(&outcome), &calibration);
  EXPECT_EQ(outcome, CalibrationOutcome::kFailed);
}

TEST(ControlLoopCalibration, CancelBeforeTheLoopTookItHandsItBackAtOnce) {
  LoopRig rig;
  FakeCalibration calibration;
  ASSERT_TRUE(rig.loop->start_calibration(&calibration));
  rig.loop->cancel_calibration();
  CalibrationOutcome outcome = CalibrationOutcome::kNone;
  EXPECT_EQ(rig.loop->take_finished_calibration(&outcome), &calibration);
  EXPECT_EQ(outcome, CalibrationOutcome::kCancelled);
  rig.step(3);
  EXPECT_EQ(calibration.steps, 0);  // never stepped
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle);
}

}  // namespace
}  // namespace swivel::rt
