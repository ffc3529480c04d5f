// SPDX-License-Identifier: Apache-2.0
// The serial port and the bus transactions against the emulated servos on a pty: the happy
// path, motion under goals, and each injectable fault as the host sees it.

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <thread>

#include "swivel/clock.hpp"
#include "swivel/dynamixel/bus.hpp"
#include "swivel/dynamixel/emulator.hpp"
#include "swivel/dynamixel/serial_port.hpp"

namespace dxl = swivel::dynamixel;

namespace {

constexpr double kTimeout = 0.05;

struct Rig {
  explicit Rig(std::vector<std::uint8_t> ids = {1, 2}, std::uint32_t baud = 1000000)
      : emulator([&] {
          dxl::Emulator::Options o;
          o.ids = std::move(ids);
          return o;
        }()) {
    port.open(emulator.port(), baud);
  }
  dxl::Emulator emulator;
  dxl::SerialPort port;
  dxl::Bus bus{port};

  dxl::BusResult write_u8(std::uint8_t id, std::uint16_t address, std::uint8_t value,
                          std::uint8_t& error) {
    const std::uint8_t data[] = {value};
    return bus.write(id, address, data, kTimeout, error);
  }
};

}  // namespace

TEST(DynamixelSerial, OpensAtStandardAndNonStandardRates) {
  dxl::Emulator emulator(dxl::Emulator::Options{});
  dxl::SerialPort port;
  port.open(emulator.port(), 4000000);
  EXPECT_TRUE(port.is_open());
  EXPECT_EQ(port.actual_baud(), 4000000U);
  port.open(emulator.port(), 2250000);  // not a Bxxx constant: termios2 BOTHER
  EXPECT_EQ(port.actual_baud(), 2250000U);
  port.close();
  EXPECT_FALSE(port.is_open());
  EXPECT_THROW(port.open("/nonexistent/tty", 57600), std::system_error);
}

TEST(DynamixelBus, PingsReadsAndWrites) {
  Rig rig;
  std::uint8_t error = 0xFF;
  EXPECT_EQ(rig.bus.ping(1, kTimeout, error), dxl::BusResult::kOk);
  EXPECT_EQ(error, 0);
  EXPECT_EQ(rig.bus.ping(2, kTimeout, error), dxl::BusResult::kOk);
  EXPECT_EQ(rig.bus.ping(3, 0.01, error), dxl::BusResult::kTimeout);

  std::uint8_t model[2] = {};
  ASSERT_EQ(rig.bus.read(1, 0, model, kTimeout, error), dxl::BusResult::kOk);
  EXPECT_EQ(model[0] | (model[1] << 8), 1020);

  ASSERT_EQ(rig.write_u8(1, dxl::address::kOperatingMode, dxl::operating_mode::kVelocity, error),
            dxl::BusResult::kOk);
  EXPECT_EQ(error, 0);
  EXPECT_EQ(rig.emulator.operating_mode(1), dxl::operating_mode::kVelocity);
  ASSERT_EQ(rig.write_u8(1, dxl::address::kTorqueEnable, 1, error), dxl::BusResult::kOk);
  // The EEPROM is locked while the torque is on.
  ASSERT_EQ(rig.write_u8(1, dxl::address::kOperatingMode, 4, error), dxl::BusResult::kOk);
  EXPECT_EQ(error, static_cast<std::uint8_t>(dxl::ErrorNumber::kAccessError));
  EXPECT_EQ(rig.emulator.operating_mode(1), dxl::operating_mode::kVelocity);
  const auto writes = rig.emulator.torque_writes();
  ASSERT_EQ(writes.size(), 1U);
  EXPECT_EQ(writes[0].id, 1);
  EXPECT_EQ(writes[0].value, 1);
}

TEST(DynamixelBus, SyncWriteDrivesAndSyncReadFollows) {
  Rig rig;
  std::uint8_t error = 0;
  ASSERT_EQ(rig.write_u8(1, dxl::address::kOperatingMode, 1, error), dxl::BusResult::kOk);
  ASSERT_EQ(rig.write_u8(2, dxl::address::kOperatingMode, 4, error), dxl::BusResult::kOk);
  const std::uint8_t ids[] = {1, 2};
  const std::uint8_t on[] = {1, 1};
  ASSERT_TRUE(rig.bus.sync_write(dxl::address::kTorqueEnable, 1, ids, on));
  // ID 1: 100 units = 22.9 rpm; ID 2: to 1000 counts.
  std::uint8_t goals[8];
  dxl::put_u32(goals, 100);
  dxl::put_u32(goals + 4, 0);
  ASSERT_TRUE(rig.bus.sync_write(dxl::address::kGoalVelocity, 4, ids, goals));
  const std::uint8_t one_id[] = {2};
  dxl::put_u32(goals, 1000);
  ASSERT_TRUE(rig.bus.sync_write(dxl::address::kGoalPosition, 4, one_id, {goals, 4}));
  const auto start = std::chrono::steady_clock::now();
  std::array<dxl::SyncReply, 2> first{};
  ASSERT_TRUE(rig.bus.sync_read(dxl::address::kPresentVelocity, 8, ids, first, kTimeout));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  std::array<dxl::SyncReply, 2> replies{};
  ASSERT_TRUE(rig.bus.sync_read(dxl::address::kPresentVelocity, 8, ids, replies, kTimeout));
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const auto& r : replies) {
    ASSERT_EQ(r.result, dxl::BusResult::kOk);
    EXPECT_EQ(r.error, 0);
  }
  EXPECT_EQ(dxl::get_i32(replies[0].data, 0), 100);  // present velocity
  const double expected = 100 * 0.229 / 60.0 * 4096.0 * elapsed_s;
  const double moved = dxl::get_i32(replies[0].data, 4) - dxl::get_i32(first[0].data, 4);
  EXPECT_NEAR(moved, expected, 0.1 * expected + 20);
  EXPECT_EQ(dxl::get_i32(replies[1].data, 4), 1000);  // reached its goal (2 rev/s max)
}

TEST(DynamixelBus, SilentServoTimesOutAloneAndCrcErrorsAreCounted) {
  Rig rig({1, 2, 3});
  const std::uint8_t ids[] = {1, 2, 3};
  std::array<dxl::SyncReply, 3> replies{};
  rig.emulator.set_silent(2, true);
  ASSERT_TRUE(rig.bus.sync_read(dxl::address::kPresentVelocity, 8, ids, replies, 0.02));
  EXPECT_EQ(replies[0].result, dxl::BusResult::kOk);
  EXPECT_EQ(replies[1].result, dxl::BusResult::kTimeout);
  EXPECT_EQ(replies[2].result, dxl::BusResult::kOk);
  rig.emulator.set_silent(2, false);
  rig.emulator.set_corrupt_crc(3, true);
  ASSERT_TRUE(rig.bus.sync_read(dxl::address::kPresentVelocity, 8, ids, replies, 0.02));
  EXPECT_EQ(replies[1].result, dxl::BusResult::kOk);
  EXPECT_EQ(replies[2].result, dxl::BusResult::kCrcError);
  EXPECT_EQ(rig.bus.crc_errors(), 1U);
  std::uint8_t error = 0;
  EXPECT_EQ(rig.bus.ping(3, kTimeout, error), dxl::BusResult::kCrcError);
  EXPECT_EQ(rig.bus.crc_errors(), 2U);
}

TEST(DynamixelBus, HardwareErrorSetsTheAlertBitAndDropsTheTorque) {
  Rig rig;
  std::uint8_t error = 0;
  ASSERT_EQ(rig.write_u8(2, dxl::address::kTorqueEnable, 1, error), dxl::BusResult::kOk);
  rig.emulator.set_hardware_error(2, dxl::hardware_error::kOverheating);
  EXPECT_EQ(rig.emulator.torque_enable(2), 0);
  const std::uint8_t ids[] = {1, 2};
  std::array<dxl::SyncReply, 2> replies{};
  ASSERT_TRUE(rig.bus.sync_read(dxl::address::kPresentVelocity, 8, ids, replies, kTimeout));
  EXPECT_EQ(replies[0].error, 0);
  EXPECT_EQ(replies[1].error, dxl::kAlertBit);
  std::uint8_t status[1] = {};
  ASSERT_EQ(rig.bus.read(2, dxl::address::kHardwareErrorStatus, status, kTimeout, error),
            dxl::BusResult::kOk);
  EXPECT_STREQ(dxl::hardware_error_text(status[0]), "overheating");
  // The torque stays off while the error stands.
  ASSERT_EQ(rig.write_u8(2, dxl::address::kTorqueEnable, 1, error), dxl::BusResult::kOk);
  EXPECT_EQ(error & 0x7F, static_cast<int>(dxl::ErrorNumber::kResultFail));
  EXPECT_EQ(rig.emulator.torque_enable(2), 0);
}

TEST(DynamixelBus, SlowRepliesMissAShortTimeoutOnly) {
  Rig rig;
  rig.emulator.set_reply_delay(1, 0.03);
  std::uint8_t error = 0;
  EXPECT_EQ(rig.bus.ping(1, 0.01, error), dxl::BusResult::kTimeout);
  usleep(50000);  // let the late reply arrive; the next request drops it
  EXPECT_EQ(rig.bus.ping(1, 0.2, error), dxl::BusResult::kOk);
  EXPECT_EQ(rig.bus.ping(2, 0.01, error), dxl::BusResult::kOk);
}

TEST(DynamixelBus, TimedWireTakesTheBytesTime) {
  dxl::Emulator::Options o;
  o.ids = {1, 2, 3, 4, 5, 6, 7, 8};
  o.baud = 57600;
  dxl::Emulator emulator(o);
  dxl::SerialPort port;
  port.open(emulator.port(), 57600);
  dxl::Bus bus(port);
  std::array<dxl::SyncReply, 8> replies{};
  const double start = swivel::monotonic_s();
  ASSERT_TRUE(bus.sync_read(dxl::address::kPresentVelocity, 8, o.ids, replies, 0.5));
  const double took = swivel::monotonic_s() - start;
  for (const auto& r : replies) EXPECT_EQ(r.result, dxl::BusResult::kOk);
  // Request 22 bytes + 8 replies of 19 bytes = 174 bytes of 10 bits at 57600 bit/s.
  EXPECT_GT(took, 174 * 10.0 / 57600 * 0.95);
  EXPECT_LT(took, 174 * 10.0 / 57600 + 0.02);
}

// An unplugged adapter reads as a port error, not as servos that stay silent: a request
// waiting for its statuses when the device goes, and every one after.
TEST(DynamixelBus, AHungUpPortIsAnErrorNotASilentServo) {
  Rig rig;
  std::array<dxl::SyncReply, 2> replies{};
  const std::uint8_t ids[] = {1, 2};
  ASSERT_TRUE(rig.bus.sync_read(dxl::address::kPresentPosition, 4, ids, replies, kTimeout));
  rig.emulator.set_silent(1, true);  // the request below is still waiting when it goes
  std::thread unplug([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    rig.emulator.disconnect();
  });
  const double start = swivel::monotonic_s();
  EXPECT_FALSE(rig.bus.sync_read(dxl::address::kPresentPosition, 4, ids, replies, 1.0));
  EXPECT_LT(swivel::monotonic_s() - start, 0.5) << "noticed at once, not at the timeout";
  unplug.join();
  std::uint8_t error = 0;
  EXPECT_EQ(rig.bus.ping(1, kTimeout, error), dxl::BusResult::kIoError);
  EXPECT_FALSE(rig.bus.sync_read(dxl::address::kPresentPosition, 4, ids, replies, kTimeout));
}
