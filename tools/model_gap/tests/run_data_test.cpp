// SPDX-License-Identifier: Apache-2.0
// RunData from run logs as they come: without gyro or commands, and with wrapped steering.

#include "swivel/model_gap/run_data.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include "gap_fixtures.hpp"
#include "swivel/model_gap/run_log_adapter.hpp"
#include "swivel/model_gap/sensor_replay.hpp"
#include "swivel/run_log.hpp"

namespace swivel::model_gap {
namespace {

RunLog parse(const std::string& text) {
  std::istringstream in(text);
  return parse_run_log(in, "run.csv");
}

constexpr const char* kHead =
    "# swivel-run 1\n# robot: bench\n# drivetrain: differential\n"
    "t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw\n";

TEST(RunData, ALogWithoutGyroOrCommandsSaysSoAndHoldsNaN) {
  const RunData d = to_run_data(parse(std::string(kHead) + "0,,,,0,0,,0,0,0\n"
                                                           "0.05,,,,0.1,0.2,,0.01,0,0.1\n"));
  EXPECT_FALSE(d.has_gyro);
  EXPECT_FALSE(d.has_commands);
  ASSERT_EQ(d.size(), 2U);
  EXPECT_TRUE(std::isnan(d.gyro_radps[1]));
  EXPECT_TRUE(std::isnan(d.cmd_vx_mps[0]));
  EXPECT_TRUE(std::isnan(d.cmd_wz_radps[1]));
  EXPECT_EQ(d.wheel_rad[1][1], 0.2);
  EXPECT_EQ(d.truth_x_m[1], 0.01);
}

TEST(RunData, AMixedLogHasNoGyroChannelButKeepsItsSamples) {
  const RunData d = to_run_data(parse(std::string(kHead) + "0,0.1,0,0,0,0,0.5,,,\n"
                                                           "0.05,0.1,0,0,0.1,0.2,,,,\n"));
  EXPECT_FALSE(d.has_gyro);  // one row without a sample: not a complete gyro channel
  EXPECT_TRUE(d.has_commands);
  EXPECT_EQ(d.gyro_radps[0], 0.5);
  EXPECT_TRUE(std::isnan(d.gyro_radps[1]));
  EXPECT_EQ(d.cmd_vx_mps[1], 0.1);

  const RunData full = to_run_data(parse(std::string(kHead) + "0,0,0,0,0,0,0.5,,,\n"));
  EXPECT_TRUE(full.has_gyro);
  EXPECT_TRUE(full.has_commands);
}

TEST(RunData, WrappedSteeringReadsLikeItsUnwrappedTwin) {
  // Two casters: one turns through +pi twice, the other through -pi; the twin log holds the
  // same angles unwrapped.
  constexpr int kRows = 300;
  RunLog twin;
  twin.source = "twin.csv";
  twin.header.robot = "cart";
  twin.header.drivetrain = DrivetrainKind::kSwpc;
  twin.header.module_count = 2;
  RunLog wrapped = twin;
  for (int k = 0; k < kRows; ++k) {
    RunLogSample s;
    s.t_s = 0.01 * k;
    s.wheel_rad = {0.02 * k, -0.03 * k};
    s.steer_rad[0] = 3.0 + 0.05 * k;
    s.steer_rad[1] = -2.5 - 0.04 * k;
    s.has_truth = true;
    s.truth = Pose2{0.001 * k, 0.0, 3.1 + 0.002 * k};
    twin.samples.push_back(s);
    for (std::size_t i = 0; i < 2; ++i) {
      s.steer_rad[i] = std::remainder(s.steer_rad[i], 2.0 * std::numbers::pi);
    }
    s.truth.yaw_rad = std::remainder(s.truth.yaw_rad, 2.0 * std::numbers::pi);
    wrapped.samples.push_back(s);
  }
  ASSERT_GT(twin.samples.back().steer_rad[0], 5.0 * std::numbers::pi);
  const RunData a = to_run_data(wrapped);
  const RunData b = to_run_data(twin);
  ASSERT_EQ(a.steer_rad.size(), 2U);
  for (std::size_t i = 0; i < 2; ++i) {
    for (int k = 0; k < kRows; ++k) {
      ASSERT_NEAR(a.steer_rad[i][k], b.steer_rad[i][k], 1e-12)
          << "module " << i + 1 << " row " << k;
    }
  }
  for (int k = 0; k < kRows; ++k) {
    ASSERT_NEAR(a.truth_yaw_rad[k], b.truth_yaw_rad[k], 1e-12) << "row " << k;
  }
}

// A RunData built in code rather than read by load_run may lack a column; the replay refuses it
// by name instead of reading past the end.
TEST(RunData, AHandBuiltRunMissingAColumnIsRefusedByName) {
  const RobotModel nominal = testing::robot("docent");
  RunData run;
  run.source = "by hand";
  run.wheel_rad.assign(2, {});
  for (int k = 0; k < 20; ++k) {
    run.t_s.push_back(0.05 * k);
    run.wheel_rad[0].push_back(0.0);
    run.wheel_rad[1].push_back(0.0);
    run.gyro_radps.push_back(0.0);
    run.truth_x_m.push_back(0.0);
    run.truth_y_m.push_back(0.0);
    run.truth_yaw_rad.push_back(0.0);
  }
  const auto message = [&nominal](const RunData& r) {
    try {
      const SensorReplay replay(nominal, r, 1.0);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message(run).find("column cmd_vx_mps has 0 values for 20 rows"), std::string::npos)
      << message(run);
  run.cmd_vx_mps.assign(20, 0.0);
  run.cmd_vy_mps.assign(20, 0.0);
  run.cmd_wz_radps.assign(20, 0.0);
  run.wheel_rad[1].pop_back();
  EXPECT_NE(message(run).find("column wheel 2 has 19 values"), std::string::npos) << message(run);
  run.wheel_rad.pop_back();
  EXPECT_NE(message(run).find("1 wheel and 0 steering columns for 2 modules"), std::string::npos)
      << message(run);
  run.wheel_rad.emplace_back(20, 0.0);
  EXPECT_EQ(message(run), "accepted");
}

}  // namespace
}  // namespace swivel::model_gap
