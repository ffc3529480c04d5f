// SPDX-License-Identifier: Apache-2.0
// swiveld on emulated DYNAMIXEL servos reached through a symbolic link (as a udev rule names
// a USB adapter): the adapter unplugged while driving is a fault naming the port; `swivelctl
// clear` is refused, naming the port and the cause, until it is back, then recovers on the
// new device and the robot drives again. DDS domain 86, loopback only.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "dynamixel_daemon_config.hpp"
#include "process_util.hpp"
#include "swivel/dynamixel/emulator.hpp"

namespace {

namespace dxl = swivel::dynamixel;
using swivel::test::Child;
using swivel::test::make_test_dir;
using swivel::test::servo_ids;
using swivel::test::source_dir;
using swivel::test::swivelctl;
using swivel::test::swiveld_exe;
using swivel::test::ToolRun;
using swivel::test::write_config;
using namespace std::chrono_literals;

constexpr int kDomain = 86;

ToolRun clear() {
  return swivelctl(
      {"clear", "--robot", "docent", "--domain", std::to_string(kDomain), "--timeout", "10"});
}

}  // namespace

TEST(SwiveldDynamixelRecovery, ClearRecoversAnUnpluggedAdapterOnceItIsBack) {
  dxl::Emulator emulator(servo_ids({1, 2}));
  const std::string dir = make_test_dir("dxl_unplug");
  const std::string link = dir + "/dxl";
  std::filesystem::create_symlink(emulator.port(), link);
  const std::string dds = "dds:\n  domain_id: " + std::to_string(kDomain) +
                          "\n  config: " + source_dir() + "/config/dds/loopback.xml\n";
  const std::string config =
      write_config(dir, "docent", swivel::test::docent_params(link),
                   "    - {vx_mps: 0.2, wz_radps: 0.3, duration_s: 600}\n", "encoders", dds);
  Child daemon(swiveld_exe(), {"--config", config});
  ASSERT_FALSE(daemon.wait_for(2s)) << "exited early:\n" << daemon.err();
  ASSERT_NE(emulator.goal_velocity(1), 0) << "not driving:\n" << daemon.err();

  emulator.disconnect();
  std::filesystem::remove(link);  // the device and its link go
  ASSERT_TRUE(daemon.wait_for_err("safe stop (dynamixel: port lost: ", 5s)) << daemon.err();

  const ToolRun refused = clear();
  EXPECT_NE(refused.exit_code, 0) << refused.out << refused.err;
  const std::string said = refused.out + refused.err;
  EXPECT_NE(said.find("refused to re-activate: dynamixel: " + link + ": cannot open"),
            std::string::npos)
      << said;
  EXPECT_EQ(said.find("ID 1"), std::string::npos) << "the port's fault, not a servo's: " << said;

  emulator.reconnect();
  std::filesystem::create_symlink(emulator.port(), link);
  const ToolRun cleared = clear();
  EXPECT_EQ(cleared.exit_code, 0) << cleared.out << cleared.err;
  EXPECT_NE(cleared.out.find("cleared hardware_error (dynamixel: port lost: "), std::string::npos)
      << cleared.out << cleared.err;
  // Driving again, through the new device.
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (emulator.goal_velocity(1) == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_NE(emulator.goal_velocity(1), 0) << daemon.err();
  EXPECT_EQ(emulator.torque_enable(1), 1);
  EXPECT_GT(emulator.bus_watchdog(1), 0) << "watchdog armed again";

  daemon.signal(SIGTERM);
  const auto status = daemon.wait_for(5s);
  ASSERT_TRUE(status) << "still running 5 s after SIGTERM";
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << daemon.err();
  EXPECT_EQ(emulator.torque_enable(1), 0);
  EXPECT_EQ(emulator.torque_enable(2), 0);
  std::filesystem::remove_all(dir);  // kept when an assertion ends the test early
}
