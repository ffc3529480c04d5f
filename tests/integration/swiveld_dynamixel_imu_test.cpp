// SPDX-License-Identifier: Apache-2.0
// The real swiveld with the `dynamixel` plugin on emulated servos (the docent's wheels) and
// the gyro from a ROS 2 IMU driver, as config/swiveld_dynamixel_imu.yaml composes a real
// robot: the test publishes sensor_msgs/Imu on rt/it_dxl_imu/imu. The wheels drive straight
// while the IMU reports a steady turn, and the estimated heading follows the IMU's integral,
// not the wheels; when the IMU stops, sensor_stale names the topic and the wheels stop.
// DDS domain 83.

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "dds_test_util.hpp"
#include "dynamixel_daemon_config.hpp"
#include "process_util.hpp"
#include "ros2_imu_publisher.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/dynamixel/emulator.hpp"
#include "swiveld_status_lines.hpp"

namespace swivel::test {
namespace {

using dds::test::ImuPublisher;
using namespace std::chrono_literals;

constexpr std::uint32_t kDomain = 83;
constexpr const char* kImuTopic = "rt/it_dxl_imu/imu";
// The IMU's turn while the wheels drive straight: the two disagree by less than the odometry
// check allows (0.2 rad/s + 10 %), so only the heading tells which one the estimate follows.
constexpr double kImuYawRateRadps = 0.1;
constexpr double kWindowS = 3.0;
// The status line prints t to 0.01 s and yaw to 0.001 rad; the wheels would give 0.
constexpr double kHeadingToleranceRad = 0.01;

std::string dds_section() {
  return "dds:\n  domain_id: " + std::to_string(kDomain) + "\n  config: " + source_dir() +
         "/config/dds/loopback.xml\n"
         "  ros2:\n    enabled: true\n    namespace: it_dxl_imu\n"
         "    imu: {rate_hz: 200, max_age_s: 0.5, startup_grace_s: 10}\n";
}

TEST(SwiveldDynamixelImu, HeadingFollowsTheRos2ImuNotTheWheelsAndItsSilenceStopsTheRobot) {
  dynamixel::Emulator emulator(servo_ids({1, 2}));
  const std::string dir = make_test_dir("dxl_imu");
  const std::string config =
      write_config(dir, "docent", docent_params(emulator.port()),
                   "    - {vx_mps: 0.2, duration_s: 600}\n", "gyro", dds_section());
  Child daemon(swiveld_exe(), {"--config", config});
  dds::Participant client({kDomain, dds::tool_config_uri()});
  ImuPublisher imu(client, kImuTopic, /*reliable=*/false);
  ASSERT_TRUE(dds::test::wait_for([&] { return imu.matched(); }))
      << "swiveld's IMU reader did not match\n"
      << daemon.err();

  // Streaming the turn until the heading shows it (the wheels alone keep it near zero), then
  // for the measuring window.
  std::vector<StatusLine> lines;
  ASSERT_TRUE(imu.stream_until(0.0, 0.0, kImuYawRateRadps,
                               [&] {
                                 lines = status_lines(daemon.out());
                                 return !lines.empty() && lines.back().yaw_rad > 0.05;
                               }))
      << "the heading never turned with the IMU\n"
      << daemon.out() << daemon.err();
  const StatusLine first = lines.back();
  const std::int32_t left_start = emulator.present_position(1);
  const std::int32_t right_start = emulator.present_position(2);
  ASSERT_TRUE(imu.stream_until(0.0, 0.0, kImuYawRateRadps, [&] {
    lines = status_lines(daemon.out());
    return lines.back().t_s >= first.t_s + kWindowS;
  })) << daemon.out();
  const StatusLine last = lines.back();
  const std::int32_t left_turned = emulator.present_position(1) - left_start;
  const std::int32_t right_turned = emulator.present_position(2) - right_start;
  const std::int32_t left_goal = emulator.goal_velocity(1);
  const std::int32_t right_goal = emulator.goal_velocity(2);

  // The wheels drive straight: equal goals and equal turns (the right servo is mounted
  // reversed), so their heading stays put.
  EXPECT_GT(left_goal, 0);
  EXPECT_EQ(left_goal, -right_goal);
  EXPECT_GT(left_turned, 1000) << "the wheels did not turn";
  EXPECT_LE(std::abs(left_turned + right_turned), left_turned / 100)
      << "left " << left_turned << ", right " << right_turned << " counts";
  EXPECT_NE(last.line.find("mode velocity fault none"), std::string::npos) << last.line;
  // The heading follows the IMU's integral.
  const double imu_integral_rad = kImuYawRateRadps * (last.t_s - first.t_s);
  const double heading_change_rad = last.yaw_rad - first.yaw_rad;
  std::printf("heading change %.4f rad over %.2f s, IMU integral %.4f rad (error %.4f rad)\n",
              heading_change_rad, last.t_s - first.t_s, imu_integral_rad,
              heading_change_rad - imu_integral_rad);
  EXPECT_NEAR(heading_change_rad, imu_integral_rad, kHeadingToleranceRad) << first.line << "\n"
                                                                          << last.line;
  EXPECT_NE(daemon.err().find(std::string("gyro from ") + kImuTopic + " (sensor_msgs/Imu"),
            std::string::npos)
      << daemon.err();

  // The IMU stops: sensor_stale names the topic, the wheels' goals go to zero and stay there
  // while the script still commands 0.2 m/s.
  const std::string stale = std::string("fault sensor_stale (#1): safe stop (") + kImuTopic +
                            ": no IMU sample for over 0.5 s)";
  ASSERT_TRUE(daemon.wait_for_err(stale, 10s)) << daemon.err();
  ASSERT_TRUE(dds::test::wait_for(
      [&] { return emulator.goal_velocity(1) == 0 && emulator.goal_velocity(2) == 0; }, 5s))
      << "the wheels did not stop: goals " << emulator.goal_velocity(1) << ", "
      << emulator.goal_velocity(2);
  // The lines printed from now on show the robot at rest in safe stop.
  const std::size_t at_rest = status_lines(daemon.out()).size() + 1;
  ASSERT_TRUE(dds::test::wait_for(
      [&] {
        lines = status_lines(daemon.out());
        return lines.size() > at_rest && lines.back().t_s >= lines[at_rest].t_s + 0.5;
      },
      5s))
      << daemon.out();
  const StatusLine& rest = lines[at_rest];
  EXPECT_NE(rest.line.find("mode safe_stop fault sensor_stale"), std::string::npos) << rest.line;
  EXPECT_NE(lines.back().line.find("mode safe_stop fault sensor_stale"), std::string::npos)
      << lines.back().line;
  EXPECT_NEAR(lines.back().x_m, rest.x_m, 1e-3) << rest.line << "\n" << lines.back().line;
  EXPECT_EQ(emulator.goal_velocity(1), 0);
  EXPECT_EQ(emulator.goal_velocity(2), 0);

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(10s), 0) << daemon.err();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace swivel::test
