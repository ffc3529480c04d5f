// SPDX-License-Identifier: Apache-2.0
// The real swiveld with the `dynamixel` hardware plugin against emulated servos on a
// pseudo-terminal: the differential docent and the four-module SWPC robot drive their
// scripts with the odometry following; a silent servo, a run of CRC errors and a hardware
// error bit each stop the robot with a message naming the servo; SIGTERM switches the torque
// of every servo off.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "dynamixel_daemon_config.hpp"
#include "process_util.hpp"
#include "swivel/dynamixel/emulator.hpp"
#include "swivel/dynamixel/protocol.hpp"
#include "swiveld_status_lines.hpp"

namespace {

namespace dxl = swivel::dynamixel;
using swivel::test::Child;
using swivel::test::docent_params;
using swivel::test::make_test_dir;
using swivel::test::servo_ids;
using swivel::test::status_lines;
using swivel::test::StatusLine;
using swivel::test::swiveld_exe;
using swivel::test::write_config;
using namespace std::chrono_literals;

constexpr const char* kArc = "    - {vx_mps: 0.2, wz_radps: 0.3, duration_s: 600}\n";

// Every ID's last Torque Enable write is 0, made at or after `after_s` (CLOCK_MONOTONIC).
void expect_torque_off(const dxl::Emulator& emulator, const std::vector<std::uint8_t>& ids,
                       double after_s) {
  const auto writes = emulator.torque_writes();
  for (const std::uint8_t id : ids) {
    std::optional<dxl::Emulator::TorqueWrite> last;
    for (const auto& w : writes) {
      if (w.id == id) last = w;
    }
    ASSERT_TRUE(last) << "no Torque Enable write to ID " << int(id);
    EXPECT_EQ(last->value, 0) << "ID " << int(id);
    EXPECT_GE(last->time_s, after_s) << "ID " << int(id);
    EXPECT_EQ(emulator.torque_enable(id), 0) << "ID " << int(id);
  }
}

double monotonic_s() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace

TEST(SwiveldDynamixel, DocentDrivesTheArcAndSigtermSwitchesTheTorqueOff) {
  dxl::Emulator emulator(servo_ids({1, 2}));
  const std::string dir = make_test_dir("dxl_docent");
  const std::string config = write_config(dir, "docent", docent_params(emulator.port()), kArc);
  Child daemon(swiveld_exe(), {"--config", config, "--no-dds"});
  ASSERT_FALSE(daemon.wait_for(3s)) << "exited early:\n" << daemon.err();
  EXPECT_EQ(emulator.torque_enable(1), 1);
  EXPECT_EQ(emulator.torque_enable(2), 1);
  EXPECT_EQ(emulator.operating_mode(1), dxl::operating_mode::kVelocity);
  const double sent_s = monotonic_s();
  daemon.signal(SIGTERM);
  const auto status = daemon.wait_for(5s);
  ASSERT_TRUE(status) << "still running 5 s after SIGTERM";
  ASSERT_TRUE(WIFEXITED(*status)) << daemon.err();
  EXPECT_EQ(WEXITSTATUS(*status), 0) << daemon.err();
  EXPECT_NE(daemon.err().find("stopped cleanly: robot at zero velocity"), std::string::npos)
      << daemon.err();
  expect_torque_off(emulator, {1, 2}, sent_s);
  EXPECT_EQ(emulator.goal_velocity(1), 0);

  const auto lines = status_lines(daemon.out());
  ASSERT_GE(lines.size(), 15U) << daemon.out();
  const StatusLine& last = lines.back();
  EXPECT_NE(last.line.find("fault none"), std::string::npos) << last.line;
  // On the arc (radius 0.2/0.3) as far as the time allows, less a start-up delay.
  const double r = 0.2 / 0.3;
  ASSERT_GT(last.t_s, 2.0) << last.line;
  EXPECT_NEAR(last.x_m, r * std::sin(last.yaw_rad), 0.02) << last.line;
  EXPECT_NEAR(last.y_m, r * (1.0 - std::cos(last.yaw_rad)), 0.02) << last.line;
  EXPECT_LE(last.yaw_rad, 0.3 * last.t_s + 0.03) << last.line;
  EXPECT_GE(last.yaw_rad, 0.3 * (last.t_s - 0.5)) << last.line;
  std::filesystem::remove_all(dir);  // kept when an assertion ends the test early
}

TEST(SwiveldDynamixel, SwpcFourModulesDriveTheSquareAndSigtermSwitchesTheTorqueOff) {
  const std::vector<std::uint8_t> ids = {1, 11, 2, 12, 3, 13, 4, 14};
  dxl::Emulator emulator(servo_ids(ids));
  const std::string dir = make_test_dir("dxl_swpc4");
  std::string params =
      "{port: " + emulator.port() + ", reply_timeout_s: 0.2, stale_timeout_s: 1.0, modules: [";
  for (int m = 1; m <= 4; ++m) {
    params += (m == 1 ? "" : ", ") + std::string("{wheel: {id: ") + std::to_string(m) +
              "}, steer: {id: " + std::to_string(10 + m) + "}}";
  }
  params += "]}";
  const std::string config = write_config(dir, "swpc4", params,
                                          "    - {vx_mps: 0.2, duration_s: 2.0}\n"
                                          "    - {vy_mps: 0.2, duration_s: 600}\n");
  Child daemon(swiveld_exe(), {"--config", config, "--no-dds"});
  ASSERT_FALSE(daemon.wait_for(4s)) << "exited early:\n" << daemon.err();
  for (int m = 1; m <= 4; ++m) {
    EXPECT_EQ(emulator.operating_mode(static_cast<std::uint8_t>(10 + m)),
              dxl::operating_mode::kExtendedPosition);
  }
  const double sent_s = monotonic_s();
  daemon.signal(SIGTERM);
  const auto status = daemon.wait_for(5s);
  ASSERT_TRUE(status) << "still running 5 s after SIGTERM";
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << daemon.err();
  expect_torque_off(emulator, ids, sent_s);

  const auto lines = status_lines(daemon.out());
  ASSERT_GE(lines.size(), 20U) << daemon.out();
  const StatusLine& last = lines.back();
  EXPECT_NE(last.line.find("fault none"), std::string::npos) << last.line << "\n" << daemon.err();
  // 2 s forward at 0.2 m/s, then sideways: about 0.4 m ahead (less the casters turning at
  // the start) and moving left, without rotating.
  EXPECT_GT(last.x_m, 0.25) << last.line;
  EXPECT_LT(last.x_m, 0.45) << last.line;
  EXPECT_GT(last.y_m, 0.05) << last.line;
  EXPECT_NEAR(last.yaw_rad, 0.0, 0.05) << last.line;
  std::filesystem::remove_all(dir);  // kept when an assertion ends the test early
}

namespace {

struct FaultCase {
  const char* name;
  void (*inject)(dxl::Emulator&);
  const char* message;
};

void check_fault_stops_robot(const FaultCase& fault) {
  SCOPED_TRACE(fault.name);
  dxl::Emulator emulator(servo_ids({1, 2}));
  const std::string dir = make_test_dir(std::string("dxl_fault_") + fault.name);
  const std::string config = write_config(dir, "docent", docent_params(emulator.port()), kArc);
  Child daemon(swiveld_exe(), {"--config", config, "--no-dds"});
  ASSERT_FALSE(daemon.wait_for(1.5s)) << "exited early:\n" << daemon.err();
  ASSERT_NE(emulator.goal_velocity(1), 0) << "not driving:\n" << daemon.err();
  fault.inject(emulator);
  const std::string expected =
      std::string("fault hardware_error (#1): safe stop (") + fault.message + ")";
  ASSERT_TRUE(daemon.wait_for_err(expected, 5s)) << daemon.err();
  std::this_thread::sleep_for(0.6s);
  // Stopped: the healthy wheel's goal is zero and the pose no longer changes.
  EXPECT_EQ(emulator.goal_velocity(1), 0);
  const auto before = status_lines(daemon.out());
  std::this_thread::sleep_for(0.5s);
  const auto after = status_lines(daemon.out());
  ASSERT_FALSE(before.empty());
  ASSERT_GT(after.size(), before.size());
  EXPECT_NE(after.back().line.find("mode safe_stop fault hardware_error"), std::string::npos)
      << after.back().line;
  EXPECT_NEAR(after.back().x_m, before.back().x_m, 1e-3);
  EXPECT_NEAR(after.back().yaw_rad, before.back().yaw_rad, 1e-3);
  EXPECT_GT(after.back().x_m, 0.05) << "it had been driving";
  daemon.signal(SIGTERM);
  ASSERT_TRUE(daemon.wait_for(5s));
  // Switched off even with the faulty servo: the healthy one confirms.
  const auto writes = emulator.torque_writes();
  ASSERT_FALSE(writes.empty());
  EXPECT_EQ(emulator.torque_enable(1), 0);
  std::filesystem::remove_all(dir);  // kept when an assertion ends the test early
}

}  // namespace

TEST(SwiveldDynamixel, SilentServoStopsTheRobotNamingIt) {
  check_fault_stops_robot({"silence", [](dxl::Emulator& e) { e.set_silent(2, true); },
                           "dynamixel ID 2 (right wheel): no status packet in time"});
}

TEST(SwiveldDynamixel, CrcRunStopsTheRobotNamingIt) {
  check_fault_stops_robot({"crc", [](dxl::Emulator& e) { e.set_corrupt_crc(1, true); },
                           "dynamixel ID 1 (left wheel): 3 CRC errors in a row"});
}

TEST(SwiveldDynamixel, HardwareErrorBitStopsTheRobotWithItsMeaning) {
  check_fault_stops_robot(
      {"hwerror",
       [](dxl::Emulator& e) { e.set_hardware_error(2, dxl::hardware_error::kOverheating); },
       "dynamixel ID 2 (right wheel): HW error: overheating"});
}

// The daemon killed outright (no shutdown): the servos' Bus Watchdog, armed at activation and
// fed by every bus cycle, stops each of them within its period by itself (e-Manual "Bus
// Watchdog(98)": the servo stops, the value turns to -1). Without it the wheels kept their
// last goals.
TEST(SwiveldDynamixel, SigkillLeavesTheServosStoppedByTheirWatchdog) {
  dxl::Emulator emulator(servo_ids({1, 2}));
  const std::string dir = make_test_dir("dxl_sigkill");
  constexpr double kWatchdogS = 0.26;  // 13 x 20 ms
  const std::string params = "{port: " + emulator.port() +
                             ", reply_timeout_s: 0.1, stale_timeout_s: 1.0, bus_watchdog_s: 0.26, "
                             "left: {id: 1}, right: {id: 2, direction: -1}}";
  const std::string config = write_config(dir, "docent", params, kArc);
  Child daemon(swiveld_exe(), {"--config", config, "--no-dds"});
  ASSERT_FALSE(daemon.wait_for(2s)) << "exited early:\n" << daemon.err();
  ASSERT_NE(emulator.goal_velocity(1), 0) << "not driving:\n" << daemon.err();
  EXPECT_EQ(emulator.bus_watchdog(1), 13);
  EXPECT_EQ(emulator.bus_watchdog(2), 13);
  EXPECT_TRUE(emulator.watchdog_expiries().empty()) << "expired while the daemon ran";
  const double killed_s = monotonic_s();
  daemon.signal(SIGKILL);
  ASSERT_TRUE(daemon.wait_for(2s));
  std::this_thread::sleep_for(0.6s);
  const auto expiries = emulator.watchdog_expiries();
  for (const std::uint8_t id : std::vector<std::uint8_t>{1, 2}) {
    std::optional<dxl::Emulator::WatchdogExpiry> expiry;
    for (const auto& e : expiries) {
      if (e.id == id) expiry = e;
    }
    ASSERT_TRUE(expiry) << "ID " << int(id) << " still driving";
    // From its last instruction packet, sent before the kill: the watchdog time after it, as
    // the emulator's thread took it in (up to 50 ms late on a loaded machine).
    EXPECT_LE(expiry->time_s - killed_s, kWatchdogS + 0.05) << "ID " << int(id);
    EXPECT_EQ(emulator.bus_watchdog(id), dxl::kBusWatchdogExpired) << "ID " << int(id);
    EXPECT_EQ(emulator.present_velocity(id), 0) << "ID " << int(id);
  }
  const std::int32_t before = emulator.present_position(1);
  std::this_thread::sleep_for(0.2s);
  (void)emulator.present_velocity(1);  // advances the emulated motors to now
  EXPECT_EQ(emulator.present_position(1), before) << "the wheel still turns";
  std::filesystem::remove_all(dir);  // kept when an assertion ends the test early
}

// A shutdown that cannot confirm every servo's torque is off says so and exits non-zero
// (a service manager sees a failed stop), instead of "stopped cleanly" and 0.
TEST(SwiveldDynamixel, ShutdownWithTorqueOffNotConfirmedExitsNonZero) {
  dxl::Emulator emulator(servo_ids({1, 2}));
  const std::string dir = make_test_dir("dxl_unconfirmed");
  const std::string config = write_config(dir, "docent", docent_params(emulator.port()), kArc);
  Child daemon(swiveld_exe(), {"--config", config, "--no-dds"});
  ASSERT_FALSE(daemon.wait_for(1.5s)) << "exited early:\n" << daemon.err();
  emulator.set_silent(2, true);
  ASSERT_TRUE(daemon.wait_for_err("no status packet in time", 5s)) << daemon.err();
  daemon.signal(SIGTERM);
  const auto status = daemon.wait_for(5s);
  ASSERT_TRUE(status) << "still running 5 s after SIGTERM";
  ASSERT_TRUE(WIFEXITED(*status)) << daemon.err();
  EXPECT_NE(WEXITSTATUS(*status), 0) << daemon.err();
  EXPECT_NE(daemon.err().find("dynamixel ID 2 (right wheel): torque off not confirmed"),
            std::string::npos)
      << daemon.err();
  EXPECT_NE(daemon.err().find("stopped, but the drives were not confirmed off"), std::string::npos)
      << daemon.err();
  EXPECT_EQ(daemon.err().find("stopped cleanly"), std::string::npos) << daemon.err();
  EXPECT_EQ(emulator.torque_enable(1), 0) << "the servo that answers is off";
  std::filesystem::remove_all(dir);  // kept when an assertion ends the test early
}

// Every reply 3 ms slower from some time on (a busier adapter or host), with stale_timeout_s
// 0.5 and corners after it: the plugin learns the new quickest exchange, so its readings keep
// a known sampling time and the corners pass without an encoder-jump fault (with the
// all-time quickest exchange, every later reading was untimed and the first corner faulted).
TEST(SwiveldDynamixel, ALastingLatencyRiseTripsNoFaultAtTheCorners) {
  dxl::Emulator emulator(servo_ids({1, 2}));
  const std::string dir = make_test_dir("dxl_latency");
  const std::string params = "{port: " + emulator.port() +
                             ", reply_timeout_s: 0.2, stale_timeout_s: 0.5, left: {id: 1}, "
                             "right: {id: 2, direction: -1}}";
  const std::string config = write_config(dir, "docent", params,
                                          "    - {vx_mps: 0.2, wz_radps: 0.6, duration_s: 2.5}\n"
                                          "    - {vx_mps: 0.2, wz_radps: -0.6, duration_s: 1.0}\n"
                                          "    - {vx_mps: 0.2, wz_radps: 0.6, duration_s: 1.0}\n"
                                          "    - {vx_mps: 0.2, wz_radps: -0.6, duration_s: 1.0}\n"
                                          "    - {vx_mps: 0.0, duration_s: 600}\n");
  Child daemon(swiveld_exe(), {"--config", config, "--no-dds"});
  ASSERT_FALSE(daemon.wait_for(1s)) << "exited early:\n" << daemon.err();
  emulator.set_reply_delay(1, 0.003);
  emulator.set_reply_delay(2, 0.003);
  ASSERT_FALSE(daemon.wait_for(6s)) << "exited early:\n" << daemon.err();
  const auto lines = status_lines(daemon.out());
  ASSERT_GE(lines.size(), 40U) << daemon.out();
  const StatusLine& last = lines.back();
  EXPECT_NE(last.line.find("fault none"), std::string::npos) << last.line << "\n" << daemon.err();
  EXPECT_EQ(daemon.err().find("encoder"), std::string::npos) << daemon.err();
  // At rest, the heading from the encoders against the servos' own positions (the docent:
  // wheel radius 0.075 m, track 0.40 m; the right servo mounted reversed).
  const double left_rad = emulator.present_position(1) * 2.0 * M_PI / 4096.0;
  const double right_rad = -emulator.present_position(2) * 2.0 * M_PI / 4096.0;
  const double true_yaw = 0.075 * (right_rad - left_rad) / 0.40;
  EXPECT_NEAR(last.yaw_rad, true_yaw, 0.01) << last.line;
  EXPECT_GT(last.x_m, 0.3) << "it drove the corners: " << last.line;
  daemon.signal(SIGTERM);
  ASSERT_TRUE(daemon.wait_for(5s));
  std::filesystem::remove_all(dir);  // kept when an assertion ends the test early
}
