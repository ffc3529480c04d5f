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
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "alloc_guard.hpp"
#include "swivel/clock.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/dynamixel/bus.hpp"
#include "swivel/dynamixel/emulator.hpp"
#include "swivel/dynamixel/serial_port.hpp"

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

// The same timeouts for a caster robot whose `modules` list is given.
std::string swpc_params(const std::string& port, const std::string& modules) {
  return "{port: " + port + ", reply_timeout_s: 0.2, stale_timeout_s: 1.0, modules: [" + modules +
         "]}";
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
            swpc_params(emulator.port(),
                        "{wheel: {id: 1}, steer: {id: 11, zero_offset_rad: 0.5}},"
                        "{wheel: {id: 2}, steer: {id: 12, gear_ratio: 3}},"
                        "{wheel: {id: 3, direction: -1}, steer: {id: 13, direction: -1}},"
                        "{wheel: {id: 4}, steer: {id: 14}}"));
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

namespace {

// The left wheel's angle from the plugin at `now` against the emulated servo's own position
// at the same instant (ID 1: direction 1, ratio 1).
double left_angle_error(DynamixelHardware& hw, dxl::Emulator& emulator, HardwareState& s,
                        Status& status) {
  const double now = swivel::monotonic_s();
  status = hw.read(now, s);
  (void)emulator.present_velocity(1);  // advances the emulated motors to now
  const double truth = emulator.present_position(1) * 2.0 * kPi / 4096.0;
  return s.wheel_angle_rad[0] - truth;
}

std::string temp_dir(const std::string& name) {
  std::string dir = ::testing::TempDir() + "dxl_" + name + "_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// A daemon configuration file holding the drivetrain section the plugin compares the servos'
// Velocity Limit with.
std::string drivetrain_file(const std::string& dir, const std::string& drivetrain_yaml) {
  std::string path = dir + "/swiveld.yaml";
  std::ofstream(path) << "drivetrain: " << drivetrain_yaml << "\n";
  return path;
}

void configure_from(DynamixelHardware& hw, const RobotModel& model, const std::string& yaml,
                    const std::string& config_file) {
  PluginContext ctx;
  ctx.params = YAML::Load(yaml);
  ctx.config_file = config_file;
  ctx.params_path = "hardware.params";
  ctx.robot = &model;
  ctx.period_s = 0.001;
  hw.configure(ctx);
}

}  // namespace

TEST(DynamixelHardware, BusWatchdogIsArmedFedAndDisarmed) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  // The test's reply timeout (0.2 s) makes the least watchdog 0.402 s: 21 x 20 ms.
  configure(hw, model, diff_params(emulator.port(), ", bus_watchdog_s: 0.402"));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  EXPECT_EQ(emulator.bus_watchdog(1), 21);
  EXPECT_EQ(emulator.bus_watchdog(2), 21);
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.5, s), Status::kOk) << hw.last_error();
  EXPECT_TRUE(emulator.watchdog_expiries().empty()) << "the bus cycles feed it";
  ASSERT_EQ(hw.deactivate(), Status::kOk) << hw.last_error();
  EXPECT_EQ(emulator.bus_watchdog(1), 0);
  EXPECT_EQ(emulator.bus_watchdog(2), 0);
}

// A servo whose watchdog expired (it missed the bus's packets: a stalled host, a noisy
// line) stands and refuses goals without a word to a Sync Write: the plugin reads it back
// and faults naming it; a clear re-arms it.
TEST(DynamixelHardware, AnExpiredWatchdogIsAFaultNamingTheServo) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.1, s), Status::kOk) << hw.last_error();
  const std::uint8_t armed = emulator.bus_watchdog(2);
  ASSERT_GT(armed, 0);
  emulator.expire_bus_watchdog(2);
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 3.0, s), Status::kError);
  EXPECT_STREQ(hw.last_error(), "dynamixel ID 2 (right wheel): bus watchdog expired");
  hw.on_error(hw.last_error());
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  EXPECT_EQ(emulator.bus_watchdog(2), armed);
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.3, s), Status::kOk) << hw.last_error();
  EXPECT_NE(emulator.goal_velocity(2), 0);
  hw.deactivate();
}

TEST(DynamixelHardware, RefusesAWatchdogShorterThanAFewBusPeriods) {
  const RobotModel model = differential();
  DynamixelHardware hw;
  try {
    configure(hw, model,
              diff_params("/dev/null",
                          ", reply_timeout_s: 0.005, bus_period_s: 0.01, bus_watchdog_s: 0.02"));
    ADD_FAILURE() << "accepted a watchdog of two bus periods";
  } catch (const swivel::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bus_watchdog_s"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3 bus periods"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(0.03 s here)"), std::string::npos) << e.what();
  }
  // Nor one a cycle waiting for a missing status outlasts (the healthy servos would stop).
  EXPECT_THROW(
      configure(hw, model, diff_params("/dev/null", ", reply_timeout_s: 0.2, bus_watchdog_s: 0.3")),
      swivel::ConfigError);
  EXPECT_THROW(configure(hw, model, diff_params("/dev/null", ", bus_watchdog_s: 3.0")),
               swivel::ConfigError);  // above 127 x 20 ms
  EXPECT_NO_THROW(configure(hw, model, diff_params("/dev/null", ", bus_watchdog_s: 0")));
}

// A servo left with an expired watchdog (the daemon died) refuses goals until 0 is written
// to it: activation clears it, and the robot drives again.
TEST(DynamixelHardware, ActivationClearsAnExpiredWatchdog) {
  dxl::Emulator emulator(ids({1, 2}));
  {
    dxl::SerialPort port;
    port.open(emulator.port(), 1000000);
    dxl::Bus bus(port);
    std::uint8_t error = 0;
    const std::uint8_t velocity_mode[] = {dxl::operating_mode::kVelocity};
    const std::uint8_t on[] = {1};
    const std::uint8_t one_unit[] = {1};  // 20 ms
    ASSERT_EQ(bus.write(1, dxl::address::kOperatingMode, velocity_mode, 0.2, error),
              dxl::BusResult::kOk);
    ASSERT_EQ(bus.write(1, dxl::address::kTorqueEnable, on, 0.2, error), dxl::BusResult::kOk);
    ASSERT_EQ(bus.write(1, dxl::address::kBusWatchdog, one_unit, 0.2, error), dxl::BusResult::kOk);
    const double start = swivel::monotonic_s();
    while (emulator.bus_watchdog(1) != dxl::kBusWatchdogExpired &&
           swivel::monotonic_s() - start < 2.0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_EQ(emulator.bus_watchdog(1), dxl::kBusWatchdogExpired);
  }
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(2.0, 2.0), 0.2, s), Status::kOk) << hw.last_error();
  EXPECT_GT(emulator.goal_velocity(1), 0) << "goals still read-only";
  EXPECT_NE(emulator.present_velocity(1), 0);
  hw.deactivate();
}

// An unplugged USB adapter: a port fault naming the port; a clear (activate()) is refused
// with the port and the cause while it is away, and once it is back (a udev symbolic link
// to the new device) closes the dead descriptor, reopens and drives again.
TEST(DynamixelHardware, AnUnpluggedAdapterIsAPortFaultAndAClearReopensIt) {
  dxl::Emulator emulator(ids({1, 2}));
  const std::string dir = temp_dir("unplug");
  const std::string link = dir + "/ttyDXL";
  std::filesystem::create_symlink(emulator.port(), link);
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(link));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.1, s), Status::kOk) << hw.last_error();

  emulator.disconnect();
  std::filesystem::remove(link);  // udev removes the link with the device
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 3.0, s), Status::kError);
  EXPECT_EQ(std::string(hw.last_error()), "dynamixel: port lost: " + link);
  hw.on_error(hw.last_error());
  EXPECT_EQ(hw.activate(), Status::kError);
  EXPECT_NE(std::string(hw.last_error()).find(link + ": cannot open"), std::string::npos)
      << hw.last_error();

  emulator.reconnect();
  std::filesystem::create_symlink(emulator.port(), link);
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  ASSERT_EQ(run(hw, wheels(1.0, 1.0), 0.2, s), Status::kOk) << hw.last_error();
  EXPECT_GT(emulator.goal_velocity(1), 0) << "the new port receives the goals";
  EXPECT_EQ(emulator.torque_enable(1), 1);
  ASSERT_EQ(hw.deactivate(), Status::kOk) << hw.last_error();
  EXPECT_EQ(emulator.torque_enable(1), 0);
  std::filesystem::remove_all(dir);
}

TEST(DynamixelHardware, DeactivateOnALostPortSaysTheTorqueOffIsNotConfirmed) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  const std::string port = emulator.port();
  configure(hw, model, diff_params(port));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  emulator.disconnect();
  EXPECT_EQ(hw.deactivate(), Status::kError);
  EXPECT_EQ(std::string(hw.last_error()),
            "dynamixel: " + port + ": port error: torque off not confirmed");
}

// The quickest exchange is learnt again after a lasting rise in latency (3 ms more per
// reply): readings get a known sampling time again and the angles keep following the
// servos through changes of direction, with stale_timeout_s as long as 0.5 s.
TEST(DynamixelHardware, AnglesFollowTheServosAfterALastingLatencyRise) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  PluginContext ctx;
  ctx.params = YAML::Load("{port: " + emulator.port() +
                          ", reply_timeout_s: 0.2, stale_timeout_s: 0.5, left: {id: 1}, "
                          "right: {id: 2}}");
  ctx.robot = &model;
  ctx.period_s = 0.001;
  hw.configure(ctx);
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(5.0, 5.0), 0.3, s), Status::kOk) << hw.last_error();
  emulator.set_reply_delay(1, 0.003);
  emulator.set_reply_delay(2, 0.003);
  ASSERT_EQ(run(hw, wheels(5.0, 5.0), 0.7, s), Status::kOk) << hw.last_error();  // learning
  std::vector<double> errors_rad;
  errors_rad.reserve(2000);
  int timed = 0;
  int readings = 0;
  std::uint64_t last_cycle = hw.last_reading().cycle;
  const double start = swivel::monotonic_s();
  for (;;) {
    const double now = swivel::monotonic_s();
    if (now - start >= 1.2) break;
    // Reverse every 0.2 s: an extrapolation from an old reading errs by 10 rad/s x its age.
    const double rate = std::fmod(now - start, 0.4) < 0.2 ? 5.0 : -5.0;
    Status status = Status::kOk;
    const double error = left_angle_error(hw, emulator, s, status);
    ASSERT_EQ(status, Status::kOk) << hw.last_error();
    ASSERT_EQ(hw.write(wheels(rate, rate)), Status::kOk);
    errors_rad.push_back(std::abs(error));
    if (hw.last_reading().cycle != last_cycle) {
      last_cycle = hw.last_reading().cycle;
      ++readings;
      if (hw.last_reading().sample_time_known) ++timed;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  // Off by the extra delay times the rate (0.015 rad), and by up to a bus cycle at 10 rad/s at
  // a reversal. The 90th percentile: a loaded machine delays some cycles (each such reading
  // is untimed and extrapolated over), while an estimate that never learns errs by up to
  // 2 rad most of the time.
  ASSERT_FALSE(errors_rad.empty());
  std::sort(errors_rad.begin(), errors_rad.end());
  EXPECT_LT(errors_rad[errors_rad.size() * 9 / 10], 0.1) << "max " << errors_rad.back();
  EXPECT_GT(timed, readings / 2) << "readings with a known sampling time: " << timed << " of "
                                 << readings;
  hw.deactivate();
}

// A status with a bad CRC carries nothing: that servo's last position keeps its own time, so
// the angle stays on the servo's path instead of lagging by rate x the bad replies' span.
TEST(DynamixelHardware, BadCrcRepliesChangeNeitherPositionNorItsTime) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port(), ", max_crc_errors: 1000"));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(5.0, 5.0), 0.3, s), Status::kOk) << hw.last_error();
  double worst_rad = 0.0;
  const double start = swivel::monotonic_s();
  bool corrupt = false;
  bool restored = false;
  for (;;) {
    const double now = swivel::monotonic_s();
    if (now - start >= 0.5) break;
    if (!corrupt && now - start > 0.1) corrupt = (emulator.set_corrupt_crc(1, true), true);
    // 80 ms of bad replies: 0.4 rad of lag at 5 rad/s had they taken the new time.
    if (!restored && now - start > 0.18) restored = (emulator.set_corrupt_crc(1, false), true);
    Status status = Status::kOk;
    const double error = left_angle_error(hw, emulator, s, status);
    ASSERT_EQ(status, Status::kOk) << hw.last_error();
    ASSERT_EQ(hw.write(wheels(5.0, 5.0)), Status::kOk);
    worst_rad = std::max(worst_rad, std::abs(error));
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_GT(hw.last_reading().crc_errors, 5U);
  EXPECT_LT(worst_rad, 0.1);
  hw.deactivate();
}

TEST(DynamixelHardware, RefusesAVelocityLimitBelowTheDrivetrainsMaximum) {
  dxl::Emulator emulator(ids({1, 2}));
  emulator.set_velocity_limit(2, 100);  // 22.9 rpm: 2.40 rad/s, 1.20 at the wheel (2:1)
  const std::string dir = temp_dir("velocity_limit");
  const std::string file =
      drivetrain_file(dir, "{plugin: differential, params: {max_wheel_rate_radps: 5.0}}");
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure_from(hw, model, diff_params(emulator.port()), file);
  EXPECT_EQ(hw.activate(), Status::kError);
  const std::string message = hw.last_error();
  EXPECT_NE(message.find("dynamixel ID 2 (right wheel): Velocity Limit 100 (1.20 rad/s at the "
                         "wheel) is below " +
                         file + ": drivetrain.params.max_wheel_rate_radps = 5 rad/s"),
            std::string::npos)
      << message;
  EXPECT_EQ(emulator.torque_enable(2), 0);

  // The drivetrain's default (20 rad/s for differential) counts when the key is absent.
  const std::string defaulted = drivetrain_file(dir, "{plugin: differential}");
  configure_from(hw, model, diff_params(emulator.port()), defaulted);
  EXPECT_EQ(hw.activate(), Status::kError);
  EXPECT_NE(std::string(hw.last_error()).find("max_wheel_rate_radps (its default) = 20"),
            std::string::npos)
      << hw.last_error();
  std::filesystem::remove_all(dir);
}

// Clamped where the configuration says so: the servo gets its limit, not a goal it would
// ignore (which left it turning at the old goal).
TEST(DynamixelHardware, ClampsWheelGoalsToTheVelocityLimitWhenConfigured) {
  dxl::Emulator emulator(ids({1, 2}));
  emulator.set_velocity_limit(1, 100);
  const std::string dir = temp_dir("velocity_clamp");
  const std::string file =
      drivetrain_file(dir, "{plugin: differential, params: {max_wheel_rate_radps: 5.0}}");
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure_from(hw, model, diff_params(emulator.port(), ", over_velocity_limit: clamp"), file);
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  HardwareState s;
  ASSERT_EQ(run(hw, wheels(4.0, 1.0), 0.2, s), Status::kOk) << hw.last_error();
  EXPECT_EQ(emulator.goal_velocity(1), 100);
  EXPECT_EQ(emulator.goal_velocity(2), -std::lround(1.0 * 60.0 / (2.0 * kPi) / 0.229 * 2.0));
  hw.deactivate();

  // Without the clamp, a goal beyond the limit (no drivetrain maximum to check at start) is
  // a fault naming the servo, and the wheels stop.
  DynamixelHardware strict;
  configure(strict, model, diff_params(emulator.port()));
  ASSERT_EQ(strict.activate(), Status::kOk) << strict.last_error();
  ASSERT_EQ(run(strict, wheels(4.0, 1.0), 3.0, s), Status::kError);
  EXPECT_STREQ(strict.last_error(), "dynamixel ID 1 (left wheel): goal above Velocity Limit");
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_EQ(emulator.goal_velocity(1), 0);
  strict.deactivate();
  std::filesystem::remove_all(dir);
}

TEST(DynamixelHardware, RefusesAServoThatIsNotXSeries) {
  dxl::Emulator::Options options = ids({1, 2});
  options.model_number = 350;  // XL-320: another control table
  dxl::Emulator emulator(options);
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  EXPECT_EQ(hw.activate(), Status::kError);
  EXPECT_STREQ(hw.last_error(),
               "dynamixel ID 1 (left wheel): model number 350 is not an X-series servo (the "
               "control table this plugin uses)");
  EXPECT_STREQ(DynamixelHardware::model_name(1020), "XM430-W350");
  EXPECT_STREQ(DynamixelHardware::model_name(1060), "XL430-W250");
}

TEST(DynamixelHardware, StartUpRidesOutLostStatusPackets) {
  dxl::Emulator emulator(ids({1, 2}));
  emulator.drop_replies(2, 2);  // the ping and its first retry go unanswered
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  EXPECT_EQ(emulator.torque_enable(2), 1);
  hw.deactivate();
  emulator.drop_replies(1, DynamixelHardware::kSetupAttempts);  // a ping never answered
  EXPECT_EQ(hw.activate(), Status::kError);
  EXPECT_STREQ(hw.last_error(), "dynamixel ID 1 (left wheel): does not answer a ping");
}

TEST(DynamixelHardware, OperatingModeIsWrittenOnlyWhenItDiffers) {
  dxl::Emulator emulator(ids({1, 2}));
  const RobotModel model = differential();
  DynamixelHardware hw;
  configure(hw, model, diff_params(emulator.port()));
  for (int clear = 0; clear < 3; ++clear) {
    ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
    ASSERT_EQ(hw.deactivate(), Status::kOk) << hw.last_error();
  }
  EXPECT_EQ(emulator.operating_mode(1), dxl::operating_mode::kVelocity);
  EXPECT_EQ(emulator.eeprom_writes(1), 1) << "position mode (factory) to velocity, once";
  EXPECT_EQ(emulator.eeprom_writes(2), 1);
}

TEST(DynamixelHardware, WarnsAboutAnAdapterLatencyTimerAboveOneMillisecond) {
  const std::string dir = temp_dir("latency_timer");
  std::filesystem::create_directories(dir + "/dev");
  std::ofstream(dir + "/dev/ttyUSB7") << "";
  std::filesystem::create_symlink(dir + "/dev/ttyUSB7", dir + "/dev/swivel-dxl");
  const std::string timer_dir = dir + "/sys/bus/usb-serial/devices/ttyUSB7";
  std::filesystem::create_directories(timer_dir);
  std::ofstream(timer_dir + "/latency_timer") << "16\n";
  const std::string warning =
      DynamixelHardware::latency_timer_warning(dir + "/dev/swivel-dxl", dir + "/sys");
  EXPECT_NE(warning.find("latency timer is 16 ms"), std::string::npos) << warning;
  EXPECT_NE(warning.find(dir + "/dev/swivel-dxl"), std::string::npos) << warning;
  std::ofstream(timer_dir + "/latency_timer") << "1\n";
  EXPECT_EQ(DynamixelHardware::latency_timer_warning(dir + "/dev/swivel-dxl", dir + "/sys"), "");
  // Not a USB serial adapter (a pty, a native UART): nothing to say.
  EXPECT_EQ(DynamixelHardware::latency_timer_warning("/dev/null", dir + "/sys"), "");
  std::filesystem::remove_all(dir);
}

TEST(DynamixelHardware, ExchangeFloorForgetsAnOldQuickestExchange) {
  DynamixelHardware::ExchangeFloor floor(0.25);
  for (int i = 0; i < 100; ++i) floor.add(0.01 * i, 0.001);  // 1 s at 1 ms
  EXPECT_DOUBLE_EQ(floor.value(), 0.001);
  // Blocks of 0.25 s from 0: the 1 ms of the block before 1.0 s is remembered until 1.25 s.
  for (int i = 100; i < 120; ++i) floor.add(0.01 * i, 0.004);  // 4 ms from 1.0 s on
  EXPECT_DOUBLE_EQ(floor.value(), 0.001) << "within a block of the change the old floor holds";
  for (int i = 120; i < 160; ++i) floor.add(0.01 * i, 0.004);
  EXPECT_DOUBLE_EQ(floor.value(), 0.004) << "two blocks on the new latency is the floor";
  floor.add(1.6, 0.002);
  EXPECT_DOUBLE_EQ(floor.value(), 0.002) << "a quicker one counts at once";
}

// A steering servo stops on its goal while its replies come late (a loaded host): its last
// timed velocity must not carry the angle past the goal, to snap back when the replies are
// on time again. That snap is an encoder jump to the drivetrain, a safe stop.
TEST(DynamixelHardware, SteeringThatStopsWhileRepliesAreLateDoesNotJump) {
  dxl::Emulator emulator(ids({1, 11, 2, 12, 3, 13, 4, 14}));
  const RobotModel model = swpc(4);
  DynamixelHardware hw;
  configure(hw, model,
            swpc_params(emulator.port(),
                        "{wheel: {id: 1}, steer: {id: 11}}, {wheel: {id: 2}, steer: {id: 12}},"
                        "{wheel: {id: 3}, steer: {id: 13}}, {wheel: {id: 4}, steer: {id: 14}}"));
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  ActuatorCommand steer;
  steer.module_count = 4;
  for (std::size_t m = 0; m < 4; ++m) steer.steer_rate_radps[m] = 6.0;
  const ActuatorCommand hold{4, {}, {}, {}};
  HardwareState s;
  ASSERT_EQ(run(hw, hold, 0.1, s), Status::kOk) << hw.last_error();
  ASSERT_EQ(run(hw, steer, 0.25, s), Status::kOk) << hw.last_error();
  double worst_rad = 0.0;
  HardwareState previous = s;
  const double start = swivel::monotonic_s();
  bool restored = false;
  const std::vector<std::uint8_t> steer_ids = {11, 12, 13, 14};
  for (const std::uint8_t id : steer_ids) emulator.set_reply_delay(id, 0.01);
  bool failed = false;
  swivel::test::HeapCounts counts;
  {
    // The bounded steering path runs on the loop's thread: no heap there either.
    swivel::test::AllocCounter counter;
    for (;;) {
      const double now = swivel::monotonic_s();
      if (now - start >= 0.5) break;
      if (!restored && now - start > 0.25) {
        for (const std::uint8_t id : steer_ids) emulator.set_reply_delay(id, 0.0);
        restored = true;
      }
      if (hw.read(now, s) != Status::kOk || hw.write(hold) != Status::kOk) {
        failed = true;
        break;
      }
      worst_rad = std::max(worst_rad, std::abs(s.steer_angle_rad[0] - previous.steer_angle_rad[0]));
      previous = s;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    counts = counter.counts();
  }
  ASSERT_FALSE(failed) << hw.last_error();
  EXPECT_EQ(counts.allocations, 0U);
  EXPECT_EQ(counts.deallocations, 0U);
  // 6 rad/s x 1 ms at most while it still moves; a snap back would be the last velocity
  // times the replies' lateness and more (over a radian before the goal bounded it).
  std::printf("largest one-cycle step of the steering: %.4f rad\n", worst_rad);
  EXPECT_LT(worst_rad, 0.03);
  hw.deactivate();
}
