// SPDX-License-Identifier: Apache-2.0
// The dynamixel hardware plugin in-process against the emulated bus: configuration errors,
// driving both robot kinds, each fault stopping the robot with the servo named, torque off
// on deactivate, and read()/write() free of heap use.

#include "dynamixel_hardware.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <thread>

#include "alloc_guard.hpp"
#include "swivel/clock.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/dynamixel/bus.hpp"
#include "swivel/dynamixel/emulator.hpp"

namespace dxl = swivel::dynamixel;
using swivel::ActuatorCommand;
using swivel::HardwareState;
using swivel::ModuleDriveMode;
using swivel::PluginContext;
using swivel::RobotModel;
using swivel::Status;
using swivel::plugins::DynamixelHardware;

namespace {

constexpr double kPi = 3.14159265358979323846;

RobotModel differential() {
  RobotModel m;
  m.drivetrain = swivel::DrivetrainKind::kDifferential;
  return m;
}

RobotModel swpc(std::size_t modules) {
  RobotModel m;
  m.drivetrain = swivel::DrivetrainKind::kSwpc;
  m.modules.resize(modules);
  return m;
}

dxl::Emulator::Options ids(std::vector<std::uint8_t> list) {
  dxl::Emulator::Options o;
  o.ids = std::move(list);
  return o;
}

void configure(DynamixelHardware& hw, const RobotModel& model, const std::string& yaml) {
  PluginContext ctx;
  ctx.params = YAML::Load(yaml);
  ctx.config_file = "test.yaml";
  ctx.params_path = "hardware.params";
  ctx.robot = &model;
  ctx.period_s = 0.001;
  hw.configure(ctx);
}

// Timeouts that a loaded test machine keeps (unless `extra` sets the reply timeout): the
// emulator is an ordinary thread.
std::string diff_params(const std::string& port, const std::string& extra = "") {
  const std::string timeout =
      (extra.find("reply_timeout_s") == std::string::npos ? ", reply_timeout_s: 0.2" : "") +
      std::string(", stale_timeout_s: 1.0");
  return "{port: " + port + ", left: {id: 1}, right: {id: 2, direction: -1, gear_ratio: 2.0}" +
         timeout + extra + "}";
}

// Runs a 1 kHz read/write loop for `seconds` with `command`, stamped on CLOCK_MONOTONIC like
// the loop's; returns the last status and state (stops at the first kError).
Status run(DynamixelHardware& hw, const ActuatorCommand& command, double seconds,
           HardwareState& state) {
  const double start = swivel::monotonic_s();
  for (;;) {
    const double now = swivel::monotonic_s();
    if (now - start >= seconds) break;
    if (hw.read(now, state) != Status::kOk) return Status::kError;
    if (hw.write(command) != Status::kOk) return Status::kError;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return Status::kOk;
}

ActuatorCommand wheels(double left, double right) {
  ActuatorCommand c;
  c.module_count = 2;
  c.wheel_rate_radps[0] = left;
  c.wheel_rate_radps[1] = right;
  return c;
}

}  // namespace

TEST(DynamixelHardware, RefusesBadParametersNamingTheKey) {
  const RobotModel model = differential();
  DynamixelHardware hw;
  auto message = [&](const std::string& yaml) {
    try {
      configure(hw, model, yaml);
    } catch (const swivel::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("{left: {id: 1}, right: {id: 2}}").find("port"), std::string::npos);
  EXPECT_NE(message("{port: /dev/null, left: {id: 1}, right: {id: 1}}").find("used twice"),
            std::string::npos);
  EXPECT_NE(
      message("{port: /dev/null, left: {id: 1, direction: 0}, right: {id: 2}}").find("direction"),
      std::string::npos);
  EXPECT_NE(message("{port: /dev/null, left: {id: 1, zero_offset_rad: 1}, right: {id: 2}}")
                .find("only to steering"),
            std::string::npos);
  EXPECT_NE(message("{port: /dev/null, left: {id: 1}, right: {id: 2}, bogus: 1}").find("bogus"),
            std::string::npos);
  const RobotModel four = swpc(4);
  try {
    configure(hw, four, "{port: /dev/null, modules: [{wheel: {id: 1}, steer: {id: 2}}]}");
    ADD_FAILURE() << "accepted one module for four";
  } catch (const swivel::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("expected 4 entries"), std::string::npos) << e.what();
  }
}

TEST(DynamixelHardware, EveryFaultMessageFitsTheLoopsFaultDetail) {
  // The loop keeps 63 characters of a cause: the longest IDs and names still fit whole.
  const RobotModel model = swpc(swivel::kMaxModules);
  std::string yaml = "{port: /dev/null, modules: [";
  for (unsigned m = 0; m < swivel::kMaxModules; ++m) {
    yaml += (m == 0 ? "" : ",") + std::string("{wheel: {id: ") + std::to_string(221 + 2 * m) +
            "}, steer: {id: " + std::to_string(222 + 2 * m) + "}}";
  }
  yaml += "]}";
  DynamixelHardware hw;
  configure(hw, model, yaml);
  ASSERT_EQ(hw.servos().size(), 2 * swivel::kMaxModules);
  EXPECT_STREQ(hw.message(DynamixelHardware::FaultKind::kHardwareError, 31,
                          dxl::hardware_error::kMotorEncoder),
               "dynamixel ID 252 (steer 15): HW error: motor encoder error");
  EXPECT_STREQ(hw.message(DynamixelHardware::FaultKind::kSilent, 30, 0),
               "dynamixel ID 251 (wheel 15): no status packet in time");
  for (std::size_t i = 0; i < hw.servos().size(); ++i) {
    for (const auto kind :
         {DynamixelHardware::FaultKind::kSilent, DynamixelHardware::FaultKind::kCrcRun,
          DynamixelHardware::FaultKind::kStatusError}) {
      EXPECT_LE(std::strlen(hw.message(kind, i, 0)), 63U) << hw.message(kind, i, 0);
    }
    for (unsigned bit = 0; bit < 8; ++bit) {
      const char* text = hw.message(DynamixelHardware::FaultKind::kHardwareError, i,
                                    static_cast<std::uint8_t>(1U << bit));
      EXPECT_LE(std::strlen(text), 63U) << text;
    }
  }
}

TEST(DynamixelHardware, ActivationNamesAMissingServoOrPort) {
  dxl::Emulator emulator(ids({1}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  EXPECT_EQ(hw.activate(), Status::kError);
  EXPECT_STREQ(hw.last_error(), "dynamixel ID 2 (right wheel): does not answer a ping");
  DynamixelHardware no_port;
  configure(no_port, model, diff_params("/nonexistent/ttyUSB9"));
  EXPECT_EQ(no_port.activate(), Status::kError);
  EXPECT_NE(std::string(no_port.last_error()).find("/nonexistent/ttyUSB9"), std::string::npos);
}

TEST(DynamixelHardware, DifferentialDrivesWithDirectionAndGearAndTorqueGoesOff) {
  dxl::Emulator emulator(ids({1, 2}));
  emulator.set_present_position(2, 4096);  // not at zero: angles are the servos' own
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  EXPECT_EQ(emulator.operating_mode(1), dxl::operating_mode::kVelocity);
  EXPECT_EQ(emulator.torque_enable(1), 1);
  EXPECT_EQ(emulator.torque_enable(2), 1);
  HardwareState start;
  ASSERT_EQ(run(hw, wheels(0.0, 0.0), 0.05, start), Status::kOk) << hw.last_error();
  EXPECT_NEAR(start.wheel_angle_rad[1], -kPi, 1e-3);  // one servo turn back, 2:1

  const auto t0 = std::chrono::steady_clock::now();
  HardwareState end;
  ASSERT_EQ(run(hw, wheels(2.0, 2.0), 0.5, end), Status::kOk) << hw.last_error();
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // 2 rad/s at the wheel: the right servo turns 4 rad/s backwards (2:1, mounted reversed).
  const double units = 2.0 * 60.0 / (2.0 * kPi) / 0.229;
  EXPECT_EQ(emulator.goal_velocity(1), std::lround(units));
  EXPECT_EQ(emulator.goal_velocity(2), -std::lround(2.0 * units));
  const double moved_left = end.wheel_angle_rad[0] - start.wheel_angle_rad[0];
  const double moved_right = end.wheel_angle_rad[1] - start.wheel_angle_rad[1];
  EXPECT_NEAR(moved_left, 2.0 * took, 0.15);
  EXPECT_NEAR(moved_right, 2.0 * took, 0.15);
  EXPECT_EQ(end.module_count, 2U);
  EXPECT_FALSE(end.gyro_valid);
  EXPECT_GT(hw.bus_cycles(), 100U);

  ASSERT_EQ(hw.deactivate(), Status::kOk) << hw.last_error();
  EXPECT_EQ(emulator.torque_enable(1), 0);
  EXPECT_EQ(emulator.torque_enable(2), 0);
  const auto writes = emulator.torque_writes();
  ASSERT_GE(writes.size(), 4U);
  EXPECT_EQ(writes.back().value, 0);
  EXPECT_EQ(emulator.goal_velocity(1), 0);
}

TEST(DynamixelHardware, SwpcSteersInExtendedPositionAndDrivesWheels) {
  dxl::Emulator emulator(ids({1, 11, 2, 12, 3, 13, 4, 14}));
  const RobotModel model = swpc(4);
  DynamixelHardware hw;
  configure(hw, model,
            "{port: " + emulator.port() +
                ", reply_timeout_s: 0.2, stale_timeout_s: 1.0, modules: ["
                "{wheel: {id: 1}, steer: {id: 11, zero_offset_rad: 0.5}},"
                "{wheel: {id: 2}, steer: {id: 12, gear_ratio: 3}},"
                "{wheel: {id: 3, direction: -1}, steer: {id: 13, direction: -1}},"
                "{wheel: {id: 4}, steer: {id: 14}}]}");
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  EXPECT_EQ(emulator.operating_mode(11), dxl::operating_mode::kExtendedPosition);
  EXPECT_EQ(emulator.operating_mode(1), dxl::operating_mode::kVelocity);
  ActuatorCommand c;
  c.module_count = 4;
  for (std::size_t m = 0; m < 4; ++m) {
    c.wheel_rate_radps[m] = 1.0;
    c.steer_rate_radps[m] = 1.0;
  }
  HardwareState start;
  ASSERT_EQ(run(hw, ActuatorCommand{4, {}, {}, {}}, 0.02, start), Status::kOk);
  EXPECT_NEAR(start.steer_angle_rad[0], -0.5, 1e-3);  // servo at 0, offset 0.5
  HardwareState end;
  ASSERT_EQ(run(hw, c, 0.3, end), Status::kOk) << hw.last_error();
  // Stop steering and let the position servos settle on their goals.
  HardwareState settled;
  ASSERT_EQ(run(hw, ActuatorCommand{4, {}, {}, {}}, 0.1, settled), Status::kOk);
  for (std::size_t m = 0; m < 4; ++m) {
    const double steered = settled.steer_angle_rad[m] - start.steer_angle_rad[m];
    EXPECT_NEAR(steered, 0.3, 0.06) << "module " << m;
    EXPECT_GT(settled.wheel_angle_rad[m] - start.wheel_angle_rad[m], 0.2) << "module " << m;
  }
  EXPECT_LT(emulator.goal_position(13), 0);  // reversed steering servo
  EXPECT_GT(emulator.goal_position(12), 3 * emulator.goal_position(14) - 60);
  // Locked: wheels stop, steering holds.
  for (std::size_t m = 0; m < 4; ++m) c.mode[m] = ModuleDriveMode::kLocked;
  ASSERT_EQ(run(hw, c, 0.05, end), Status::kOk);
  EXPECT_EQ(emulator.goal_velocity(1), 0);
  // Free steering is not a mode these servos do.
  c.mode[0] = ModuleDriveMode::kFreeSteer;
  EXPECT_EQ(hw.write(c), Status::kError);
  ASSERT_EQ(hw.deactivate(), Status::kOk);
  for (const std::uint8_t id : std::vector<std::uint8_t>{1, 11, 2, 12, 3, 13, 4, 14})
    EXPECT_EQ(emulator.torque_enable(id), 0);
}

TEST(DynamixelHardware, SilentServoStopsTheRobotNamingItAndAClearRecovers) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  ASSERT_EQ(hw.activate(), Status::kOk);
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(3.0, 3.0), 0.1, s), Status::kOk);
  EXPECT_NE(emulator.goal_velocity(1), 0);
  emulator.set_silent(2, true);
  ASSERT_EQ(run(hw, wheels(3.0, 3.0), 3.0, s), Status::kError);
  EXPECT_STREQ(hw.last_error(), "dynamixel ID 2 (right wheel): no status packet in time");
  hw.on_error(hw.last_error());
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_EQ(emulator.goal_velocity(1), 0) << "the bus thread stops the wheels itself";
  // The fault stays until a clear; the clear names the servo while it is still silent.
  EXPECT_EQ(hw.read(swivel::monotonic_s(), s), Status::kError);
  EXPECT_EQ(hw.activate(), Status::kError);
  EXPECT_STREQ(hw.last_error(), "dynamixel ID 2 (right wheel): does not answer a ping");
  emulator.set_silent(2, false);
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  EXPECT_EQ(run(hw, wheels(0.0, 0.0), 0.05, s), Status::kOk) << hw.last_error();
  hw.deactivate();
}

TEST(DynamixelHardware, LateRepliesAreAFaultNamingTheServo) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port(), ", reply_timeout_s: 0.1"));
  ASSERT_EQ(hw.activate(), Status::kOk);
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.1, s), Status::kOk);
  emulator.set_reply_delay(1, 0.5);
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 3.0, s), Status::kError);
  EXPECT_STREQ(hw.last_error(), "dynamixel ID 1 (left wheel): no status packet in time");
  emulator.set_reply_delay(1, 0.0);
  hw.deactivate();
}

// A reply that comes late, after the servos sampled (the host woke late for it, or the
// device answered late), leaves the instant of that sample unknown. Taken at face value it
// would make the wheel angle step back and then jump: the drivetrain's encoder-jump check.
TEST(DynamixelHardware, LateRepliesDoNotMakeTheAnglesJump) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  constexpr double kRate = 5.0;  // rad/s at the wheel
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(kRate, kRate), 0.3, s), Status::kOk) << hw.last_error();
  // The largest step of the left wheel beyond rate x dt, while its replies come 30 ms late
  // (0.15 rad at this rate) for a while and then on time again.
  double worst_rad = 0.0;
  HardwareState previous = s;
  const double start = swivel::monotonic_s();
  bool delayed = false;
  bool restored = false;
  for (;;) {
    const double now = swivel::monotonic_s();
    if (now - start >= 0.6) break;
    if (!delayed && now - start > 0.1) delayed = (emulator.set_reply_delay(1, 0.03), true);
    if (!restored && now - start > 0.3) restored = (emulator.set_reply_delay(1, 0.0), true);
    ASSERT_EQ(hw.read(now, s), Status::kOk) << hw.last_error();
    ASSERT_EQ(hw.write(wheels(kRate, kRate)), Status::kOk) << hw.last_error();
    const double step = s.wheel_angle_rad[0] - previous.wheel_angle_rad[0];
    worst_rad = std::max(worst_rad, std::abs(step - kRate * (s.stamp_s - previous.stamp_s)));
    previous = s;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_LT(worst_rad, 0.05);
  hw.deactivate();
}

TEST(DynamixelHardware, ABusThreadThatPublishesNothingIsStale) {
  // Replies slower than stale_timeout_s but within the reply timeout: the bus thread waits,
  // publishes nothing, and read() says so within the stale limit.
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  PluginContext ctx;
  ctx.params = YAML::Load("{port: " + emulator.port() +
                          ", reply_timeout_s: 1.0, stale_timeout_s: 0.05, left: {id: 1}, "
                          "right: {id: 2}}");
  ctx.robot = &model;
  ctx.period_s = 0.001;
  hw.configure(ctx);
  ASSERT_EQ(hw.activate(), Status::kOk);
  emulator.set_reply_delay(2, 0.6);
  HardwareState s;
  const double start = swivel::monotonic_s();
  ASSERT_EQ(run(hw, wheels(0.0, 0.0), 3.0, s), Status::kError);
  const double took = swivel::monotonic_s() - start;
  EXPECT_STREQ(hw.last_error(), "dynamixel: bus thread published nothing for stale_timeout_s");
  EXPECT_LT(took, 0.6) << "before the late reply came";
  emulator.set_reply_delay(2, 0.0);
  hw.deactivate();
}

TEST(DynamixelHardware, CrcErrorsAreCountedAndARunTrips) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  {
    // A generous limit: the errors are counted, the robot keeps going.
    DynamixelHardware hw;
    configure(hw, model, diff_params(emulator.port(), ", max_crc_errors: 1000"));
    ASSERT_EQ(hw.activate(), Status::kOk);
    HardwareState s;
    emulator.set_corrupt_crc(2, true);
    ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.1, s), Status::kOk) << hw.last_error();
    EXPECT_GT(hw.last_reading().crc_errors, 5U);
    EXPECT_LT(hw.last_reading().crc_errors, 1000U);
    emulator.set_corrupt_crc(2, false);
    ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.05, s), Status::kOk) << hw.last_error();
    hw.deactivate();
  }
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port(), ", max_crc_errors: 3"));
  ASSERT_EQ(hw.activate(), Status::kOk);
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.05, s), Status::kOk);
  emulator.set_corrupt_crc(2, true);
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 3.0, s), Status::kError);
  EXPECT_STREQ(hw.last_error(), "dynamixel ID 2 (right wheel): 3 CRC errors in a row");
  EXPECT_GE(hw.last_reading().crc_errors, 3U);
  emulator.set_corrupt_crc(2, false);
  hw.deactivate();
}

TEST(DynamixelHardware, HardwareErrorBitIsReportedWithItsMeaning) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  ASSERT_EQ(hw.activate(), Status::kOk);
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.05, s), Status::kOk);
  emulator.set_hardware_error(1, dxl::hardware_error::kOverload);
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 3.0, s), Status::kError);
  EXPECT_STREQ(hw.last_error(), "dynamixel ID 1 (left wheel): HW error: overload");
  EXPECT_EQ(hw.activate(), Status::kError);
  EXPECT_STREQ(hw.last_error(),
               "dynamixel ID 1 (left wheel): hardware error: overload (power-cycle or reboot "
               "the servo)");
  emulator.set_hardware_error(1, 0);
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  hw.deactivate();
}

TEST(DynamixelHardware, ReadAndWriteDoNotTouchTheHeap) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  ASSERT_EQ(hw.activate(), Status::kOk);
  HardwareState s;
  const ActuatorCommand c = wheels(1.0, -1.0);
  ASSERT_EQ(run(hw, c, 0.02, s), Status::kOk);
  swivel::test::HeapCounts counts;
  {
    swivel::test::AllocCounter counter;
    for (int i = 0; i < 300; ++i) {
      (void)hw.read(swivel::monotonic_s(), s);
      (void)hw.write(c);
      usleep(500);
    }
    emulator.set_silent(1, true);  // the fault path too
    const double start = swivel::monotonic_s();
    while (swivel::monotonic_s() - start < 3.0) {
      const Status status = hw.read(swivel::monotonic_s(), s);
      (void)hw.write(c);
      if (status != Status::kOk) break;
      usleep(500);
    }
    counts = counter.counts();
  }
  EXPECT_EQ(hw.read(swivel::monotonic_s(), s), Status::kError);
  EXPECT_EQ(counts.allocations, 0U);
  EXPECT_EQ(counts.deallocations, 0U);
  emulator.set_silent(1, false);
  hw.deactivate();
}
