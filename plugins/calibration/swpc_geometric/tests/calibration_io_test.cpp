// SPDX-License-Identifier: Apache-2.0
// Calibration logs in, calibrated model out.

#include "swivel/calibration/calibration_io.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <stdexcept>
#include <string>

namespace swivel::calibration {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// A 3-module log locked on module `locked` at `steer_rad`, motion capture every other row.
RunLog make_log(std::size_t locked, double steer_rad, const std::string& comment) {
  RunLog log;
  log.source = "run.csv";
  log.header.robot = "tri";
  log.header.drivetrain = DrivetrainKind::kSwpc;
  log.header.module_count = 3;
  if (!comment.empty()) log.header.comments = {"source: test", comment};
  for (int k = 0; k < 10; ++k) {
    RunLogSample s;
    s.t_s = 0.01 * k;
    for (std::size_t m = 0; m < 3; ++m) {
      s.wheel_rad[m] = m == locked ? 0.0 : 0.1 * k;
      s.steer_rad[m] = m == locked ? steer_rad : 0.5;
    }
    s.has_truth = k % 2 == 0;
    s.truth = Pose2{0.001 * k, 0.0, 0.02 * k};
    log.samples.push_back(s);
  }
  return log;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no exception)";
}

TEST(CalibrationIoTest, CommentRoundTripsTheLock) {
  const LockSpec lock{2, 165.0 * kDeg};
  const RunLog log = make_log(2, 165.0 * kDeg, calibration_comment(lock, 0.3));
  const std::optional<LockSpec> read = lock_from_comments(log);
  ASSERT_TRUE(read.has_value());
  EXPECT_EQ(read->locked_module, 2U);
  EXPECT_DOUBLE_EQ(*read->declared_steer_rad, 165.0 * kDeg);
  EXPECT_FALSE(lock_from_comments(make_log(0, 0.0, "")).has_value());
}

TEST(CalibrationIoTest, MalformedCommentNamesTheLog) {
  const RunLog log = make_log(0, 0.0, "calibration: locked_module two");
  EXPECT_NE(message_of([&] { lock_from_comments(log); }).find("run.csv"), std::string::npos);
  const RunLog zero = make_log(0, 0.0, "calibration: locked_module 0");
  EXPECT_NE(message_of([&] { lock_from_comments(zero); }).find("module number >= 1"),
            std::string::npos);
}

TEST(CalibrationIoTest, RunTakesMotionCaptureRowsAndTheEncoderLockedAngle) {
  const RunLog log = make_log(1, 0.8, "");
  const LockedRun run = locked_run_from_log(log, {1, std::nullopt});
  ASSERT_EQ(run.data.t_s.size(), 5U);
  EXPECT_DOUBLE_EQ(run.data.t_s[1], 0.02);
  EXPECT_DOUBLE_EQ(run.data.yaw_rad[4], 0.16);
  EXPECT_DOUBLE_EQ(run.data.wheel_angle_rad[0][2], 0.4);
  EXPECT_DOUBLE_EQ(run.locked_steer_meas_rad, 0.8);
}

TEST(CalibrationIoTest, DeclaredAngleFarFromTheEncoderIsRejected) {
  const RunLog log = make_log(1, 45.0 * kDeg, "");
  EXPECT_NO_THROW(locked_run_from_log(log, {1, 45.5 * kDeg}));
  const std::string msg = message_of([&] { locked_run_from_log(log, {1, 165.0 * kDeg}); });
  EXPECT_NE(msg.find("declared locked at 165 deg but its steering encoder reads 45 deg"),
            std::string::npos)
      << msg;
}

TEST(CalibrationIoTest, WrappedSteeringReadsLikeItsUnwrappedTwin) {
  // Locked at 180 deg, the absolute encoder flickers between +pi - e and -pi + e; module 3
  // turns through +pi while the robot moves.
  RunLog wrapped = make_log(1, 0.0, "");
  RunLog twin = wrapped;
  for (std::size_t k = 0; k < wrapped.samples.size(); ++k) {
    const double flicker = k % 2 == 0 ? -0.002 : 0.002;
    twin.samples[k].steer_rad[1] = std::numbers::pi + flicker;
    twin.samples[k].steer_rad[2] = 3.0 + 0.05 * static_cast<double>(k);
    for (std::size_t m = 1; m < 3; ++m) {
      wrapped.samples[k].steer_rad[m] =
          std::remainder(twin.samples[k].steer_rad[m], 2.0 * std::numbers::pi);
    }
  }
  const LockedRun a = locked_run_from_log(wrapped, {1, 180.0 * kDeg});
  const LockedRun b = locked_run_from_log(twin, {1, 180.0 * kDeg});
  EXPECT_NEAR(a.locked_steer_meas_rad, b.locked_steer_meas_rad, 1e-12);
  EXPECT_NEAR(a.locked_steer_meas_rad, std::numbers::pi, 0.002);
  ASSERT_EQ(a.data.steer_angle_rad[2].size(), b.data.steer_angle_rad[2].size());
  for (std::size_t k = 0; k < a.data.steer_angle_rad[2].size(); ++k) {
    EXPECT_NEAR(a.data.steer_angle_rad[2][k], b.data.steer_angle_rad[2][k], 1e-12) << k;
  }
}

TEST(CalibrationIoTest, ModuleOutOfRangeAndDifferentRobotsAreRejected) {
  const RunLog log = make_log(1, 0.8, "");
  EXPECT_NE(message_of([&] {
              locked_run_from_log(log, {3, std::nullopt});
            }).find("locked module 4 but the robot has 3 modules"),
            std::string::npos);
  RunLog other = make_log(0, 0.8, "");
  other.header.robot = "quad";
  const std::string msg = message_of([&] {
    calibration_input_from_logs({log, other}, {{1, std::nullopt}, {0, std::nullopt}});
  });
  EXPECT_NE(msg.find("robot 'quad'"), std::string::npos) << msg;
}

TEST(CalibrationIoTest, CalibratedModelReplacesOnlyTheModules) {
  RobotModel nominal;
  nominal.name = "tri";
  nominal.drivetrain = DrivetrainKind::kSwpc;
  nominal.modules.resize(3);
  nominal.sensors.wheel_encoder_counts_per_rev = 1000;
  CalibrationResult result;
  result.modules.resize(3);
  result.modules[1].params.wheel_radius_m = 0.0551;
  const RobotModel out = calibrated_model(nominal, result);
  EXPECT_EQ(out.name, "tri");
  EXPECT_EQ(out.sensors.wheel_encoder_counts_per_rev, 1000);
  EXPECT_DOUBLE_EQ(out.modules[1].wheel_radius_m, 0.0551);
  EXPECT_NEAR(calibration_options_for(nominal).steer_encoder_sigma_rad,
              2.0 * std::numbers::pi / 4096.0 / std::sqrt(12.0), 1e-15);
}

}  // namespace
}  // namespace swivel::calibration
