// SPDX-License-Identifier: Apache-2.0
// The files a run writes, read back with the project's own readers: proof of the format of
// swivel/run_log.hpp and docs/configuration.md "Robot model". Also determinism.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>
#include <string>

#include "swivel/independent/battery.hpp"
#include "swivel/independent/generator.hpp"
#include "swivel/independent/run_files.hpp"
#include "swivel/independent/simulation.hpp"
#include "swivel/independent/tour.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_log.hpp"

namespace swivel::independent {
namespace {

swivel::RunLog parse(const std::string& csv) {
  std::istringstream in(csv);
  return swivel::parse_run_log(in, "generated.csv");
}

std::vector<std::string> lines_of(const std::string& text, std::size_t count) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (lines.size() < count && std::getline(in, line)) lines.push_back(line);
  return lines;
}

class RunLogFormat : public ::testing::TestWithParam<const char*> {};

TEST_P(RunLogFormat, ParsesWithTheProjectsReaderAndCarriesEveryColumnAtItsRowsTime) {
  const BatteryCase* c = find_case(GetParam());
  ASSERT_NE(c, nullptr);
  const RunRecord record = simulate(c->spec);
  const std::string csv = run_log_csv(c->spec, record);
  const swivel::RunLog log = parse(csv);
  const bool swpc = c->spec.robot == Robot::kSwpc4;

  // The fixed lines, the declarations (what gyro_wz means in time, the motion capture's clock
  // and frame) and the generator's comment, then the header row.
  const std::vector<std::string> head = lines_of(csv, swpc ? 9 : 8);
  EXPECT_EQ(head[0], "# swivel-run 1");
  EXPECT_EQ(head[1], "# robot: " + c->robot);
  EXPECT_EQ(head[2], swpc ? "# drivetrain: swpc" : "# drivetrain: differential");
  if (swpc) {
    EXPECT_EQ(head[3], "# modules: 4");
  }
  EXPECT_EQ(head.back(), swpc ? "t,cmd_vx,cmd_vy,cmd_wz,steer_1,steer_2,steer_3,steer_4,wheel_1,"
                                "wheel_2,wheel_3,wheel_4,gyro_wz,truth_x,truth_y,truth_yaw"
                              : "t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,"
                                "truth_y,truth_yaw");
  EXPECT_EQ(log.header.robot, c->robot);
  EXPECT_EQ(log.header.drivetrain,
            swpc ? swivel::DrivetrainKind::kSwpc : swivel::DrivetrainKind::kDifferential);
  EXPECT_EQ(log.header.module_count, swpc ? 4U : 2U);
  EXPECT_TRUE(log.header.gyro_mean_over_row) << "its gyro reports the mean since the last row";

  // 100 Hz rows, strictly increasing, jittered by about 0.3 ms and never more than 1 ms.
  ASSERT_EQ(log.samples.size(), 12000U);
  double sum_sq = 0.0;
  std::size_t with_truth = 0;
  const std::vector<TourSegment> tour =
      make_tour(c->spec.robot, c->spec.steering, c->spec.seed, c->spec.duration_s);
  for (std::size_t k = 0; k < log.samples.size(); ++k) {
    const swivel::RunLogSample& s = log.samples[k];
    const RunRow& r = record.rows[k];
    if (k > 0) {
      ASSERT_GT(s.t_s, log.samples[k - 1].t_s);
    }
    const double jitter = s.t_s - 0.01 * static_cast<double>(k);
    ASSERT_LE(std::abs(jitter), 1e-3 + 1e-12);
    sum_sq += jitter * jitter;
    // The log holds exactly the generated values (shortest round-trip text).
    ASSERT_EQ(s.t_s, r.t_s);
    ASSERT_EQ(s.gyro_wz_radps, r.gyro_wz_radps);
    for (std::size_t i = 0; i < log.header.module_count; ++i) {
      ASSERT_EQ(s.wheel_rad[i], r.wheel_rad[i]);
      if (swpc) {
        ASSERT_EQ(s.steer_rad[i], r.steer_rad[i]);
      }
    }
    // The command column is the user's setpoint at the row's own time.
    const Twist cmd = setpoint_at(tour, s.t_s);
    ASSERT_EQ(s.cmd.vx_mps, cmd.vx_mps);
    ASSERT_EQ(s.cmd.vy_mps, cmd.vy_mps);
    ASSERT_EQ(s.cmd.wz_radps, cmd.wz_radps);
    ASSERT_EQ(s.has_truth, r.has_truth);
    if (s.has_truth) {
      ++with_truth;
      ASSERT_GT(s.truth.yaw_rad, -std::numbers::pi);
      ASSERT_LE(s.truth.yaw_rad, std::numbers::pi);
      // Motion capture is the pose at the row's time, up to its noise (0.3 mm, 1 mrad).
      ASSERT_NEAR(s.truth.x_m, r.true_pose.x_m, 6.0 * 0.0003);
      ASSERT_NEAR(std::remainder(s.truth.yaw_rad - r.true_pose.yaw_rad, 2.0 * std::numbers::pi),
                  0.0, 6.0 * 0.001);
    }
  }
  const double jitter_std = std::sqrt(sum_sq / static_cast<double>(log.samples.size() - 1));
  EXPECT_NEAR(jitter_std, 0.0003, 0.00003);
  // Motion capture at 100 Hz on its own clock, 0.5 % of frames lost: almost every row.
  const double share = static_cast<double>(with_truth) / static_cast<double>(log.samples.size());
  EXPECT_GT(share, 0.90);
  EXPECT_LT(share, 1.0);
}

INSTANTIATE_TEST_SUITE_P(BothRobots, RunLogFormat,
                         ::testing::Values("docent/clean/1", "swpc4/clean/1"));

TEST(RunLogFormat, NamesTheGeneratorButNotTheTrueRobot) {
  const BatteryCase* c = find_case("docent/track_width/large");
  ASSERT_NE(c, nullptr);
  RunSpec spec = c->spec;
  spec.duration_s = 5.0;
  const swivel::RunLog log = parse(generate(spec).run_csv);
  // Besides the generator, only the motion capture's clock and frame (`truth_clock: shared`,
  // `truth_frame: robot`, which the model-gap workflow reads from the comments).
  ASSERT_EQ(log.header.comments.size(), 3U);
  EXPECT_EQ(log.header.comments[0], "truth_clock: shared");
  EXPECT_EQ(log.header.comments[1], "truth_frame: robot");
  EXPECT_EQ(log.header.comments[2],
            "source: swivel-independent-run (independent robot generator), seed 108");
}

TEST(ModelFile, DocentModelParsesWithTheProjectsReaderAndStatesItsLimits) {
  RunSpec spec;
  const swivel::RobotModel m = swivel::parse_robot_model(nominal_model_yaml(spec), "docent.yaml");
  EXPECT_EQ(m.name, "docent");
  EXPECT_EQ(m.drivetrain, swivel::DrivetrainKind::kDifferential);
  EXPECT_EQ(m.differential.wheel_radius_left_m, 0.075);
  EXPECT_EQ(m.differential.wheel_radius_right_m, 0.075);
  EXPECT_EQ(m.differential.track_width_m, 0.40);
  EXPECT_EQ(m.sensors.wheel_encoder_counts_per_rev, 4096);
  EXPECT_EQ(m.sensors.gyro.scale, 1.0);
  EXPECT_EQ(m.sensors.gyro.bias_rad_s, 0.0);
  EXPECT_EQ(m.sensors.gyro.noise_rad_s, 0.002);
  EXPECT_EQ(m.sensors.motion_capture.position_noise_m, 0.0003);
  EXPECT_EQ(m.sensors.motion_capture.yaw_noise_rad, 0.001);
  EXPECT_EQ(m.sensors.motion_capture.rate_hz, 100.0);
  ASSERT_TRUE(m.limits.linear_acceleration_mps2.has_value());
  EXPECT_EQ(*m.limits.linear_acceleration_mps2, 0.6);
  ASSERT_TRUE(m.limits.angular_acceleration_radps2.has_value());
  EXPECT_EQ(*m.limits.angular_acceleration_radps2, 2.0);
  EXPECT_FALSE(m.limits.steering_rate_radps.has_value());
  EXPECT_TRUE(m.effects.empty());

  spec.model_limits = ModelLimits::kNone;
  EXPECT_FALSE(swivel::parse_robot_model(nominal_model_yaml(spec), "docent.yaml").limits.any());
  spec.model_limits = ModelLimits::kSteeringOnly;
  EXPECT_FALSE(swivel::parse_robot_model(nominal_model_yaml(spec), "docent.yaml").limits.any());
}

TEST(ModelFile, Swpc4ModelParsesWithTheProjectsReaderAndStatesItsLimits) {
  RunSpec spec;
  spec.robot = Robot::kSwpc4;
  const swivel::RobotModel m = swivel::parse_robot_model(nominal_model_yaml(spec), "swpc4.yaml");
  EXPECT_EQ(m.name, "swpc4");
  EXPECT_EQ(m.drivetrain, swivel::DrivetrainKind::kSwpc);
  ASSERT_EQ(m.modules.size(), 4U);
  const double x[] = {0.215, 0.215, -0.215, -0.215};
  const double y[] = {0.125, -0.125, -0.125, 0.125};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(m.modules[i].x_m, x[i]);
    EXPECT_EQ(m.modules[i].y_m, y[i]);
    EXPECT_EQ(m.modules[i].steering_offset_rad, 0.0);
    EXPECT_EQ(m.modules[i].caster_offset_m, 0.020);
    EXPECT_EQ(m.modules[i].wheel_radius_m, 0.055);
  }
  EXPECT_EQ(m.sensors.steering_encoder_counts_per_rev, 4096);
  ASSERT_TRUE(m.limits.steering_rate_radps.has_value());
  EXPECT_EQ(*m.limits.steering_rate_radps, 6.0);
  EXPECT_EQ(*m.limits.linear_acceleration_mps2, 0.6);
  EXPECT_TRUE(m.effects.empty());

  spec.model_limits = ModelLimits::kSteeringOnly;
  const swivel::RobotModel steering_only =
      swivel::parse_robot_model(nominal_model_yaml(spec), "swpc4.yaml");
  EXPECT_FALSE(steering_only.limits.linear_acceleration_mps2.has_value());
  EXPECT_FALSE(steering_only.limits.angular_acceleration_radps2.has_value());
  EXPECT_EQ(*steering_only.limits.steering_rate_radps, 6.0);
  spec.model_limits = ModelLimits::kNone;
  EXPECT_FALSE(swivel::parse_robot_model(nominal_model_yaml(spec), "swpc4.yaml").limits.any());
}

TEST(Determinism, SameSpecTwiceGivesByteIdenticalFiles) {
  const BatteryCase* c = find_case("swpc4/pair/steering_offset+sensor_latency");
  ASSERT_NE(c, nullptr);
  RunSpec spec = c->spec;
  spec.duration_s = 30.0;
  const GeneratedRun a = generate(spec);
  const GeneratedRun b = generate(spec);
  EXPECT_EQ(a.run_csv, b.run_csv);
  EXPECT_EQ(a.nominal_model_yaml, b.nominal_model_yaml);
  spec.seed += 1;
  EXPECT_NE(generate(spec).run_csv, a.run_csv);
}

}  // namespace
}  // namespace swivel::independent
