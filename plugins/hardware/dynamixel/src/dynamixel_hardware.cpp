// SPDX-License-Identifier: Apache-2.0
#include "dynamixel_hardware.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <numbers>
#include <system_error>

#include "swivel/clock.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/dynamixel/protocol.hpp"
#include "swivel/plugin/abi.hpp"

namespace swivel::plugins {
namespace {

namespace dxl = swivel::dynamixel;

constexpr double kRadPerCount = 2.0 * std::numbers::pi / dxl::kPositionCountsPerRev;
constexpr double kRadpsPerUnit = dxl::kVelocityUnitRpm * 2.0 * std::numbers::pi / 60.0;
constexpr double kSetupTimeoutS = 0.1;

// The hardware_error_text() meanings, in the order of hardware_messages_.
constexpr std::array<const char*, DynamixelHardware::kHardwareTexts> kHardwareTextList = {
    "input voltage error", "overheating", "motor encoder error",
    "electrical shock",    "overload",    "unknown hardware error"};

std::string format(const char* fmt, unsigned id, const std::string& name, const char* text) {
  char line[256];
  std::snprintf(line, sizeof line, fmt, id, name.c_str(), text);
  return line;
}

DynamixelHardware::Servo parse_servo(ParamReader& s, bool steering, std::uint32_t module,
                                     const std::string& name) {
  DynamixelHardware::Servo servo;
  servo.id = static_cast<std::uint8_t>(s.integer("id", 0, dxl::kMaxId));
  servo.steering = steering;
  servo.module = module;
  const int direction = s.integer_or("direction", 1, -1, 1);
  if (direction == 0) s.fail("direction", "expected 1 or -1, got 0");
  servo.direction = direction;
  servo.gear_ratio = s.number_or("gear_ratio", 1.0, 1e-3, 1e4);
  if (steering) {
    servo.zero_offset_rad = s.number_or("zero_offset_rad", 0.0, -1e3, 1e3);
  } else if (s.has("zero_offset_rad")) {
    s.fail("zero_offset_rad", "applies only to steering servos");
  }
  s.finish();
  servo.name = name;
  return servo;
}

void sleep_until(double t_s) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_s);
  ts.tv_nsec = static_cast<long>((t_s - static_cast<double>(ts.tv_sec)) * 1e9);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

DynamixelHardware::~DynamixelHardware() { stop_thread(); }

void DynamixelHardware::configure(const PluginContext& ctx) {
  if (ctx.robot == nullptr) throw ConfigError("dynamixel hardware: no robot model");
  stop_thread();
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  port_path_ = params.string("port");
  baud_ = static_cast<std::uint32_t>(params.integer_or("baud", 1000000, 9600, 20000000));
  reply_timeout_s_ = params.number_or("reply_timeout_s", 0.005, 1e-4, 1.0);
  bus_period_s_ = params.number_or("bus_period_s", 0.002, 0.0, 1.0);
  stale_timeout_s_ = params.number_or("stale_timeout_s", 0.05, 1e-3, 10.0);
  max_crc_errors_ = static_cast<std::uint32_t>(params.integer_or("max_crc_errors", 3, 1, 1000));
  std::vector<Servo> servos;
  const bool differential = ctx.robot->drivetrain == DrivetrainKind::kDifferential;
  const auto modules = static_cast<std::uint32_t>(ctx.robot->module_count());
  if (differential) {
    ParamReader left = params.child("left");
    servos.push_back(parse_servo(left, false, 0, "left wheel"));
    ParamReader right = params.child("right");
    servos.push_back(parse_servo(right, false, 1, "right wheel"));
  } else {
    const YAML::Node list = params.sequence("modules");
    if (list.size() != modules) {
      char text[96];
      std::snprintf(text, sizeof text, "expected %u entries (the robot model's modules), got %zu",
                    modules, list.size());
      params.fail("modules", text);
    }
    for (std::size_t m = 0; m < list.size(); ++m) {
      ParamReader entry = params.element(list, "modules", m);
      char name[48];
      std::snprintf(name, sizeof name, "wheel %zu", m);
      ParamReader wheel = entry.child("wheel");
      servos.push_back(parse_servo(wheel, false, static_cast<std::uint32_t>(m), name));
      std::snprintf(name, sizeof name, "steer %zu", m);
      ParamReader steer = entry.child("steer");
      servos.push_back(parse_servo(steer, true, static_cast<std::uint32_t>(m), name));
      entry.finish();
    }
  }
  for (std::size_t i = 0; i < servos.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (servos[i].id == servos[j].id) {
        params.fail(differential ? "right" : "modules",
                    format("servo ID %u is used twice (%s)", servos[i].id, servos[j].name, ""));
      }
    }
  }
  params.finish();

  servos_ = std::move(servos);
  module_count_ = modules;
  loop_period_s_ = ctx.period_s > 0.0 ? ctx.period_s : 0.001;
  stale_cycles_ =
      static_cast<std::uint32_t>(std::max(1.0, std::ceil(stale_timeout_s_ / loop_period_s_)));
  wheel_ids_.clear();
  steer_ids_.clear();
  all_ids_.clear();
  wheel_index_.clear();
  steer_index_.clear();
  wheel_servo_.fill(-1);
  steer_servo_.fill(-1);
  messages_.assign(servos_.size(), {});
  hardware_messages_.assign(servos_.size(), {});
  for (std::size_t i = 0; i < servos_.size(); ++i) {
    const Servo& s = servos_[i];
    all_ids_.push_back(s.id);
    if (s.steering) {
      steer_ids_.push_back(s.id);
      steer_index_.push_back(i);
      steer_servo_[s.module] = static_cast<std::int32_t>(i);
    } else {
      wheel_ids_.push_back(s.id);
      wheel_index_.push_back(i);
      wheel_servo_[s.module] = static_cast<std::int32_t>(i);
    }
    auto& m = messages_[i];
    m[static_cast<std::size_t>(FaultKind::kSilent)] =
        format("dynamixel ID %u (%s): %s", s.id, s.name, "no status packet in time");
    char crc_text[48];
    std::snprintf(crc_text, sizeof crc_text, "%u CRC errors in a row", max_crc_errors_);
    m[static_cast<std::size_t>(FaultKind::kCrcRun)] =
        format("dynamixel ID %u (%s): %s", s.id, s.name, crc_text);
    m[static_cast<std::size_t>(FaultKind::kStatusError)] =
        format("dynamixel ID %u (%s): %s", s.id, s.name, "error in status packet");
    for (std::size_t k = 0; k < kHardwareTextList.size(); ++k) {
      hardware_messages_[i][k] =
          format("dynamixel ID %u (%s): HW error: %s", s.id, s.name, kHardwareTextList[k]);
    }
  }
  last_error_ = "";
}

const char* DynamixelHardware::message(FaultKind kind, std::size_t servo,
                                       std::uint8_t hardware_error) const noexcept {
  if (kind == FaultKind::kPort) return "dynamixel: serial port error";
  if (servo >= messages_.size()) return "dynamixel: fault";
  if (kind == FaultKind::kHardwareError) {
    const char* text = dxl::hardware_error_text(hardware_error);
    for (std::size_t k = 0; k < kHardwareTextList.size(); ++k) {
      if (std::strcmp(text, kHardwareTextList[k]) == 0) return hardware_messages_[servo][k].c_str();
    }
    return hardware_messages_[servo].back().c_str();
  }
  return messages_[servo][static_cast<std::size_t>(kind)].c_str();
}

std::int32_t DynamixelHardware::wheel_goal(std::size_t i, double rate_radps) const noexcept {
  const Servo& s = servos_[i];
  const double units = s.direction * rate_radps * s.gear_ratio / kRadpsPerUnit;
  return static_cast<std::int32_t>(std::lround(std::clamp(units, -1e9, 1e9)));
}

std::int32_t DynamixelHardware::steer_goal(std::size_t i, double angle_rad) const noexcept {
  const Servo& s = servos_[i];
  const double counts = s.direction * (angle_rad + s.zero_offset_rad) * s.gear_ratio / kRadPerCount;
  return static_cast<std::int32_t>(std::llround(std::clamp(counts, -2e9, 2e9)));
}

double DynamixelHardware::angle_at(std::int32_t servo, double age_s) const noexcept {
  if (servo < 0) return 0.0;
  const auto i = static_cast<std::size_t>(servo);
  const Servo& s = servos_[i];
  const double rate_radps = s.direction * timed_.velocity[i] * kRadpsPerUnit / s.gear_ratio;
  return output_angle(i, timed_.position[i]) + rate_radps * age_s;
}

double DynamixelHardware::output_angle(std::size_t i, std::int32_t counts) const noexcept {
  const Servo& s = servos_[i];
  const double angle = s.direction * counts * kRadPerCount / s.gear_ratio;
  return s.steering ? angle - s.zero_offset_rad : angle;
}

bool DynamixelHardware::setup_servo(dxl::Bus& bus, std::size_t i) {
  const Servo& s = servos_[i];
  std::uint8_t error = 0;
  auto fail = [&](const char* what) {
    activate_error_ = format("dynamixel ID %u (%s): %s", s.id, s.name, what);
    return false;
  };
  dxl::BusResult r = bus.ping(s.id, kSetupTimeoutS, error);
  if (r != dxl::BusResult::kOk) {
    return fail(r == dxl::BusResult::kTimeout ? "does not answer a ping" : dxl::bus_result_text(r));
  }
  if ((error & dxl::kAlertBit) != 0) {
    std::uint8_t bits[1] = {};
    if (bus.read(s.id, dxl::address::kHardwareErrorStatus, bits, kSetupTimeoutS, error) ==
            dxl::BusResult::kOk &&
        bits[0] != 0) {
      const std::string text = std::string("hardware error: ") + dxl::hardware_error_text(bits[0]) +
                               " (power-cycle or reboot the servo)";
      return fail(text.c_str());
    }
  }
  const std::uint8_t off[] = {0};
  r = bus.write(s.id, dxl::address::kTorqueEnable, off, kSetupTimeoutS, error);
  if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) return fail("cannot switch the torque off");
  const std::uint8_t mode[] = {s.steering ? dxl::operating_mode::kExtendedPosition
                                          : dxl::operating_mode::kVelocity};
  r = bus.write(s.id, dxl::address::kOperatingMode, mode, kSetupTimeoutS, error);
  if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) {
    return fail("cannot set the operating mode");
  }
  std::uint8_t present[4] = {};
  r = bus.read(s.id, dxl::address::kPresentPosition, present, kSetupTimeoutS, error);
  if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) {
    return fail("cannot read the present position");
  }
  reading_.position[i] = dxl::get_i32(present, 0);
  reading_.velocity[i] = 0;
  return true;
}

Status DynamixelHardware::activate() {
  stop_thread();
  hold_.store(false, std::memory_order_release);
  try {
    if (!port_.is_open()) port_.open(port_path_, baud_);
  } catch (const std::system_error& e) {
    activate_error_ = std::string("dynamixel: ") + e.what();
    last_error_ = activate_error_.c_str();
    return Status::kError;
  }
  dxl::Bus bus(port_);
  reading_ = Reading{};
  for (std::size_t i = 0; i < servos_.size(); ++i) {
    if (!setup_servo(bus, i)) {
      last_error_ = activate_error_.c_str();
      return Status::kError;
    }
  }
  // Goals before the torque: wheels still, steering where it is.
  std::array<std::uint8_t, 4 * kMaxServos> data{};
  for (std::size_t k = 0; k < wheel_index_.size(); ++k) dxl::put_u32(&data[4 * k], 0);
  bool sent = wheel_ids_.empty() || bus.sync_write(dxl::address::kGoalVelocity, 4, wheel_ids_,
                                                   {data.data(), 4 * wheel_ids_.size()});
  for (std::size_t k = 0; k < steer_index_.size(); ++k) {
    const std::size_t i = steer_index_[k];
    dxl::put_u32(&data[4 * k], static_cast<std::uint32_t>(reading_.position[i]));
    start_steer_rad_[servos_[i].module] = output_angle(i, reading_.position[i]);
  }
  sent = sent && (steer_ids_.empty() || bus.sync_write(dxl::address::kGoalPosition, 4, steer_ids_,
                                                       {data.data(), 4 * steer_ids_.size()}));
  if (!sent) {
    activate_error_ = "dynamixel: cannot write to " + port_path_;
    last_error_ = activate_error_.c_str();
    return Status::kError;
  }
  for (const Servo& s : servos_) {
    const std::uint8_t on[] = {1};
    std::uint8_t error = 0;
    const dxl::BusResult r =
        bus.write(s.id, dxl::address::kTorqueEnable, on, kSetupTimeoutS, error);
    if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) {
      activate_error_ =
          format("dynamixel ID %u (%s): %s", s.id, s.name, "refuses to switch the torque on");
      last_error_ = activate_error_.c_str();
      deactivate();
      last_error_ = activate_error_.c_str();
      return Status::kError;
    }
  }
  // Nothing stale crosses into the new run.
  Reading old;
  while (readings_.take(old)) {
  }
  ActuatorCommand zero{};
  zero.module_count = module_count_;
  commands_.publish(zero);
  reading_.stamp_s = swivel::monotonic_s();
  reading_.sample_s = reading_.stamp_s;
  timed_ = reading_;
  cycles_without_reading_ = 0;
  stop_.store(false, std::memory_order_release);
  thread_ = std::thread([this, initial = reading_] { bus_loop(initial); });
  return Status::kOk;
}

void DynamixelHardware::stop_thread() noexcept {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

Status DynamixelHardware::deactivate() {
  stop_thread();
  if (!port_.is_open()) return Status::kOk;
  dxl::Bus bus(port_);
  std::array<std::uint8_t, 4 * kMaxServos> zero{};
  if (!wheel_ids_.empty()) {
    bus.sync_write(dxl::address::kGoalVelocity, 4, wheel_ids_,
                   {zero.data(), 4 * wheel_ids_.size()});
  }
  bus.sync_write(dxl::address::kTorqueEnable, 1, all_ids_, {zero.data(), all_ids_.size()});
  // Confirm with each servo; one that does not answer is named.
  Status status = Status::kOk;
  for (const Servo& s : servos_) {
    std::uint8_t torque[1] = {1};
    std::uint8_t error = 0;
    if (bus.read(s.id, dxl::address::kTorqueEnable, torque, kSetupTimeoutS, error) !=
            dxl::BusResult::kOk ||
        torque[0] != 0) {
      if (status == Status::kOk) {
        activate_error_ =
            format("dynamixel ID %u (%s): %s", s.id, s.name, "torque off not confirmed");
        last_error_ = activate_error_.c_str();
      }
      status = Status::kError;
    }
  }
  port_.close();
  return status;
}

void DynamixelHardware::on_error(const char* /*cause*/) noexcept {
  hold_.store(true, std::memory_order_release);
}

void DynamixelHardware::bus_loop(Reading r) noexcept {
  dxl::Bus bus(port_);
  std::array<dxl::SyncReply, kMaxServos> replies{};
  std::array<std::uint8_t, 4 * kMaxServos> data{};
  std::array<std::uint32_t, kMaxServos> crc_run{};
  std::array<double, kMaxModules> steer_target = start_steer_rad_;
  ActuatorCommand command{};
  command.module_count = module_count_;
  const std::span<const std::uint8_t> ids(all_ids_);
  // The statuses of the Sync Read: 11 bytes of frame and 8 of data each, 10 bits a byte.
  const double status_wire_s = static_cast<double>(19 * ids.size()) * 10.0 / baud_;
  double last_s = swivel::monotonic_s();
  double next_s = last_s;
  double quickest_exchange_s = std::numeric_limits<double>::infinity();
  while (!stop_.load(std::memory_order_acquire)) {
    const double start_s = swivel::monotonic_s();
    const double dt = std::clamp(start_s - last_s, 0.0, 0.1);
    last_s = start_s;
    commands_.take(command);
    const bool hold = hold_.load(std::memory_order_acquire) || r.fault != FaultKind::kNone;
    for (std::size_t k = 0; k < wheel_index_.size(); ++k) {
      const std::size_t i = wheel_index_[k];
      const std::uint32_t m = servos_[i].module;
      const bool still = hold || command.mode[m] == ModuleDriveMode::kLocked;
      dxl::put_u32(&data[4 * k], static_cast<std::uint32_t>(
                                     wheel_goal(i, still ? 0.0 : command.wheel_rate_radps[m])));
    }
    bool ok = wheel_ids_.empty() || bus.sync_write(dxl::address::kGoalVelocity, 4, wheel_ids_,
                                                   {data.data(), 4 * wheel_ids_.size()});
    for (std::size_t k = 0; k < steer_index_.size(); ++k) {
      const std::size_t i = steer_index_[k];
      const std::uint32_t m = servos_[i].module;
      if (!hold && command.mode[m] != ModuleDriveMode::kLocked) {
        steer_target[m] += command.steer_rate_radps[m] * dt;
      }
      dxl::put_u32(&data[4 * k], static_cast<std::uint32_t>(steer_goal(i, steer_target[m])));
    }
    ok = ok && (steer_ids_.empty() || bus.sync_write(dxl::address::kGoalPosition, 4, steer_ids_,
                                                     {data.data(), 4 * steer_ids_.size()}));
    const double request_s = swivel::monotonic_s();
    ok = ok && bus.sync_read(dxl::address::kPresentVelocity, 8, ids, replies, reply_timeout_s_);
    if (!ok && r.fault == FaultKind::kNone) r.fault = FaultKind::kPort;
    for (std::size_t i = 0; ok && i < ids.size(); ++i) {
      const dxl::SyncReply& reply = replies[i];
      FaultKind fault = FaultKind::kNone;
      std::uint8_t bits = 0;
      if (reply.result == dxl::BusResult::kOk) {
        crc_run[i] = 0;
        if ((reply.error & 0x7F) != 0) {
          fault = FaultKind::kStatusError;
        } else {
          r.velocity[i] = dxl::get_i32(reply.data, 0);
          r.position[i] = dxl::get_i32(reply.data, 4);
        }
        if ((reply.error & dxl::kAlertBit) != 0) {
          std::uint8_t status[1] = {};
          std::uint8_t error = 0;
          const dxl::BusResult hr =
              bus.read(ids[i], dxl::address::kHardwareErrorStatus, status, reply_timeout_s_, error);
          if (hr == dxl::BusResult::kOk && status[0] != 0) {
            fault = FaultKind::kHardwareError;
            bits = status[0];
          } else if (hr == dxl::BusResult::kTimeout) {
            fault = FaultKind::kSilent;
          }
        }
      } else if (reply.result == dxl::BusResult::kCrcError) {
        if (++crc_run[i] >= max_crc_errors_) fault = FaultKind::kCrcRun;
      } else {
        fault = FaultKind::kSilent;
      }
      if (fault != FaultKind::kNone && r.fault == FaultKind::kNone) {
        r.fault = fault;
        r.fault_servo = static_cast<std::uint8_t>(i);
        r.hardware_error = bits;
      }
    }
    const double end_s = swivel::monotonic_s();
    ++r.cycle;
    r.stamp_s = end_s;
    // A servo samples its present values when it takes the request and the last status
    // arrives after all of them crossed the wire: the sample is that wire time before the
    // end (a late start, on a busy host or device, then does not skew it).
    r.sample_s = std::max(request_s, end_s - status_wire_s);
    // A late end (the thread woke late for the replies, or the device answered late) moves
    // the estimate away from the true instant by as much: such a reading has no known
    // sampling time, and the loop keeps extrapolating the last one that had.
    const double exchange_s = end_s - request_s;
    if (ok) quickest_exchange_s = std::min(quickest_exchange_s, exchange_s);
    r.sample_time_known = exchange_s <= quickest_exchange_s + kSampleTimingSlackS;
    r.cycle_busy_s = end_s - start_s;
    r.crc_errors = bus.crc_errors();
    readings_.publish(r);
    bus_cycles_.fetch_add(1, std::memory_order_relaxed);
    if (bus_period_s_ > 0.0) {
      next_s += bus_period_s_;
      if (next_s < end_s) next_s = end_s;  // overran: no burst to catch up
      sleep_until(next_s);
    }
  }
}

Status DynamixelHardware::read(double stamp_s, HardwareState& out) noexcept {
  Reading fresh;
  const bool took = readings_.take(fresh);
  if (took) {
    reading_ = fresh;
    cycles_without_reading_ = 0;
  } else if (++cycles_without_reading_ > stale_cycles_) {
    last_error_ = "dynamixel: bus thread published nothing for stale_timeout_s";
    return Status::kError;
  }
  if (reading_.fault != FaultKind::kNone) {
    last_error_ = message(reading_.fault, reading_.fault_servo, reading_.hardware_error);
    return Status::kError;
  }
  // A new reading without a known sampling time is used only once the last one with it is
  // stale_timeout_s old: extrapolating that far would err more than its timing does.
  if ((took && reading_.sample_time_known) || stamp_s - timed_.sample_s > stale_timeout_s_) {
    timed_ = reading_;
  }
  // The bus and the loop are not in step: extrapolate the servos' positions from when they
  // were sampled to the loop's stamp with their present velocities, so that the loop sees
  // steady motion rather than a reading that stands still one cycle and jumps the next.
  const double age_s = std::clamp(stamp_s - timed_.sample_s, -stale_timeout_s_, stale_timeout_s_);
  out.stamp_s = stamp_s;
  out.module_count = module_count_;
  for (std::uint32_t m = 0; m < module_count_; ++m) {
    out.wheel_angle_rad[m] = angle_at(wheel_servo_[m], age_s);
    out.steer_angle_rad[m] = angle_at(steer_servo_[m], age_s);
  }
  out.gyro_valid = false;
  out.gyro_wz_radps = 0.0;
  out.motion_capture.valid = false;
  return Status::kOk;
}

Status DynamixelHardware::write(const ActuatorCommand& command) noexcept {
  if (command.module_count != module_count_) {
    last_error_ = "dynamixel: command module count differs from the robot's";
    return Status::kError;
  }
  for (std::uint32_t m = 0; m < command.module_count; ++m) {
    if (!std::isfinite(command.wheel_rate_radps[m]) ||
        !std::isfinite(command.steer_rate_radps[m])) {
      last_error_ = "dynamixel: non-finite actuator setpoint";
      return Status::kError;
    }
    if (command.mode[m] != ModuleDriveMode::kVelocity &&
        command.mode[m] != ModuleDriveMode::kLocked) {
      last_error_ = "dynamixel: drive mode not supported (velocity and locked only)";
      return Status::kError;
    }
  }
  commands_.publish(command);
  return Status::kOk;
}

}  // namespace swivel::plugins

#ifndef SWIVEL_DYNAMIXEL_NO_EXPORT
SWIVEL_EXPORT_PLUGIN(swivel::plugins::DynamixelHardware, swivel::Hardware, "dynamixel")
#endif
