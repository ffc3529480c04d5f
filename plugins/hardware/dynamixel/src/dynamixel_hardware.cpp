// SPDX-License-Identifier: Apache-2.0
#include "dynamixel_hardware.hpp"

#include <spdlog/spdlog.h>
#include <time.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
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

// A start-up exchange tried kSetupAttempts times while it gets no good status (a lost or
// corrupted packet); a port error or a status that arrived is final.
template <typename Exchange>
dxl::BusResult with_retries(Exchange exchange) {
  dxl::BusResult r = dxl::BusResult::kTimeout;
  for (int attempt = 0; attempt < DynamixelHardware::kSetupAttempts; ++attempt) {
    r = exchange();
    if (r == dxl::BusResult::kOk || r == dxl::BusResult::kIoError) return r;
  }
  return r;
}

struct Model {
  std::uint16_t number;
  const char* name;
};
// The X-series servos: their model numbers (Model Number, address 0) as the ROBOTIS
// e-Manual's control tables give them; all share the control table this plugin uses.
constexpr std::array<Model, 27> kXSeries = {{
    {1000, "XH430-W350"},  {1010, "XH430-W210"},  {1020, "XM430-W350"}, {1030, "XM430-W210"},
    {1040, "XH430-V350"},  {1050, "XH430-V210"},  {1060, "XL430-W250"}, {1070, "XC430-W150"},
    {1080, "XC430-W240"},  {1090, "2XL430-W250"}, {1100, "XH540-W270"}, {1110, "XH540-W150"},
    {1120, "XM540-W270"},  {1130, "XM540-W150"},  {1140, "XH540-V270"}, {1150, "XH540-V150"},
    {1160, "2XC430-W250"}, {1170, "XW540-T260"},  {1180, "XW540-T140"}, {1190, "XL330-M077"},
    {1200, "XL330-M288"},  {1210, "XC330-T181"},  {1220, "XC330-T288"}, {1230, "XC330-M181"},
    {1240, "XC330-M288"},  {1270, "XW430-T333"},  {1280, "XW430-T200"},
}};

}  // namespace

void DynamixelHardware::ExchangeFloor::add(double now_s, double exchange_s) noexcept {
  if (now_s - block_start_s_ >= block_s_) {
    previous_ = current_;
    current_ = 1e300;
    block_start_s_ = now_s;
  }
  current_ = std::min(current_, exchange_s);
}

double DynamixelHardware::ExchangeFloor::value() const noexcept {
  return std::min(current_, previous_);
}

const char* DynamixelHardware::model_name(std::uint16_t model) noexcept {
  for (const Model& m : kXSeries) {
    if (m.number == model) return m.name;
  }
  return nullptr;
}

std::string DynamixelHardware::latency_timer_warning(const std::string& port,
                                                     const std::string& sysfs_root) {
  std::error_code ec;
  const std::filesystem::path device = std::filesystem::canonical(port, ec);
  if (ec) return "";
  const std::string path =
      sysfs_root + "/bus/usb-serial/devices/" + device.filename().string() + "/latency_timer";
  std::ifstream in(path);
  int ms = 0;
  if (!(in >> ms) || ms <= 1) return "";
  return "dynamixel: " + port + ": the USB adapter's latency timer is " + std::to_string(ms) +
         " ms (" + path + "): each status packet may wait that long; set it to 1";
}

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
  // e-Manual "Bus Watchdog(98)": 1-127 units of 20 ms; 0 leaves it off. It must outlast a
  // bus cycle that waits for a missing status (reply_timeout_s, then the alert read) or the
  // other servos stop by themselves; by default 0.1 s, or that least time when it is longer.
  const double least_watchdog_s =
      std::max({3.0 * bus_period_s_, 2.0 * reply_timeout_s_ + bus_period_s_, 0.02});
  bus_watchdog_s_ = params.number_or("bus_watchdog_s", std::max(0.1, least_watchdog_s), 0.0,
                                     dxl::kBusWatchdogMax * dxl::kBusWatchdogUnitS);
  if (bus_watchdog_s_ > 0.0 && bus_watchdog_s_ < least_watchdog_s) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "expected 0 (off) or at least 3 bus periods and 2 reply timeouts plus a bus "
                  "period (%g s here), got %g: the watchdog would stop healthy servos",
                  least_watchdog_s, bus_watchdog_s_);
    params.fail("bus_watchdog_s", text);
  }
  watchdog_units_ = static_cast<std::uint8_t>(
      std::lround(std::ceil(bus_watchdog_s_ / dxl::kBusWatchdogUnitS - 1e-9)));
  clamp_to_velocity_limit_ =
      params.choice_or("over_velocity_limit", "refuse", {"refuse", "clamp"}) == "clamp";
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
  read_drivetrain_limits(ctx);
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
    m[static_cast<std::size_t>(FaultKind::kWatchdog)] =
        format("dynamixel ID %u (%s): %s", s.id, s.name, "bus watchdog expired");
    m[static_cast<std::size_t>(FaultKind::kVelocityLimit)] =
        format("dynamixel ID %u (%s): %s", s.id, s.name, "goal above Velocity Limit");
    for (std::size_t k = 0; k < kHardwareTextList.size(); ++k) {
      hardware_messages_[i][k] =
          format("dynamixel ID %u (%s): HW error: %s", s.id, s.name, kHardwareTextList[k]);
    }
  }
  port_message_ = "dynamixel: port lost: " + port_path_;
  last_error_ = "";
}

// The drivetrain's maximum rates, from the daemon configuration the plugin's params are in
// (drivetrain.params): the servos must be able to follow them.
void DynamixelHardware::read_drivetrain_limits(const PluginContext& ctx) {
  max_wheel_rate_radps_ = 0.0;
  max_steer_rate_radps_ = 0.0;
  YAML::Node config;
  try {
    config = YAML::LoadFile(ctx.config_file);
  } catch (const std::exception&) {
    return;  // not a file (a configuration built in memory): nothing to compare with
  }
  if (!config.IsMap() || !config["drivetrain"] || !config["drivetrain"].IsMap()) return;
  const YAML::Node drivetrain = config["drivetrain"];
  const std::string plugin =
      drivetrain["plugin"] ? drivetrain["plugin"].as<std::string>("") : std::string();
  const YAML::Node params = drivetrain["params"];
  // The drivetrains' own defaults where the key is absent (differential_drivetrain.hpp,
  // swpc_drivetrain.hpp).
  double wheel_default = 0.0;
  double steer_default = 0.0;
  if (plugin == "differential") wheel_default = 20.0;
  if (plugin == "swpc") {
    wheel_default = 40.0;
    steer_default = 12.0;
  }
  auto number = [&](const char* key, double fallback, std::string& where) {
    where = ctx.config_file + ": drivetrain.params." + key;
    try {
      if (params && params.IsMap() && params[key]) return params[key].as<double>();
    } catch (const YAML::Exception&) {
      return 0.0;  // the drivetrain itself refuses it, naming the key
    }
    if (fallback > 0.0) where += " (its default)";
    return fallback;
  };
  max_wheel_rate_radps_ = number("max_wheel_rate_radps", wheel_default, max_wheel_rate_key_);
  max_steer_rate_radps_ = number("max_steer_rate_radps", steer_default, max_steer_rate_key_);
}

const char* DynamixelHardware::message(FaultKind kind, std::size_t servo,
                                       std::uint8_t hardware_error) const noexcept {
  if (kind == FaultKind::kPort) return port_message_.c_str();
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

double DynamixelHardware::angle_at(std::int32_t servo, double stamp_s) const noexcept {
  if (servo < 0) return 0.0;
  const auto i = static_cast<std::size_t>(servo);
  const Servo& s = servos_[i];
  const double age_s =
      std::clamp(stamp_s - timed_.servo_sample_s[i], -stale_timeout_s_, stale_timeout_s_);
  const double rate_radps = s.direction * timed_.velocity[i] * kRadpsPerUnit / s.gear_ratio;
  return output_angle(i, timed_.position[i]) + rate_radps * age_s;
}

double DynamixelHardware::steer_angle_at(std::uint32_t m, double stamp_s) const noexcept {
  const std::int32_t servo = steer_servo_[m];
  if (servo < 0) return 0.0;
  // A servo that stops on its goal while its replies come late would otherwise be carried
  // past the goal by its last velocity, to snap back at the next timed reading: an encoder
  // jump to the drivetrain. The goal moves on at the commanded rate since it was written.
  const double sampled = output_angle(static_cast<std::size_t>(servo), timed_.position[servo]);
  const double goal =
      reading_.steer_goal_rad[m] +
      commanded_steer_rate_[m] * std::clamp(stamp_s - reading_.goal_s, 0.0, stale_timeout_s_);
  return std::clamp(angle_at(servo, stamp_s), std::min(sampled, goal), std::max(sampled, goal));
}

double DynamixelHardware::output_angle(std::size_t i, std::int32_t counts) const noexcept {
  const Servo& s = servos_[i];
  const double angle = s.direction * counts * kRadPerCount / s.gear_ratio;
  return s.steering ? angle - s.zero_offset_rad : angle;
}

bool DynamixelHardware::setup_servo(dxl::Bus& bus, std::size_t i) {
  Servo& s = servos_[i];
  std::uint8_t error = 0;
  auto fail = [&](const char* what) {
    activate_error_ = format("dynamixel ID %u (%s): %s", s.id, s.name, what);
    return false;
  };
  // A failing port is the port's fault, not the servo's.
  auto port_failed = [&](const char* doing) {
    activate_error_ = "dynamixel: " + port_path_ + ": port error (" + doing + ")";
    return false;
  };
  dxl::BusResult r = with_retries([&] { return bus.ping(s.id, kSetupTimeoutS, error, &s.model); });
  if (r == dxl::BusResult::kIoError) return port_failed("ping");
  if (r != dxl::BusResult::kOk) {
    return fail(r == dxl::BusResult::kTimeout ? "does not answer a ping" : dxl::bus_result_text(r));
  }
  if (model_name(s.model) == nullptr) {
    const std::string text = "model number " + std::to_string(s.model) +
                             " is not an X-series servo (the control table this plugin uses)";
    return fail(text.c_str());
  }
  if ((error & dxl::kAlertBit) != 0) {
    std::uint8_t bits[1] = {};
    if (with_retries([&] {
          return bus.read(s.id, dxl::address::kHardwareErrorStatus, bits, kSetupTimeoutS, error);
        }) == dxl::BusResult::kOk &&
        bits[0] != 0) {
      const std::string text = std::string("hardware error: ") + dxl::hardware_error_text(bits[0]) +
                               " (power-cycle or reboot the servo)";
      return fail(text.c_str());
    }
  }
  // Step by step: each write is confirmed by its status (retried while none comes).
  auto write = [&](std::uint16_t address, std::span<const std::uint8_t> data) {
    return with_retries([&] { return bus.write(s.id, address, data, kSetupTimeoutS, error); });
  };
  auto read = [&](std::uint16_t address, std::span<std::uint8_t> data) {
    return with_retries([&] { return bus.read(s.id, address, data, kSetupTimeoutS, error); });
  };
  // A watchdog that expired (the daemon died) keeps the goals read-only until 0 is written.
  const std::uint8_t off[] = {0};
  r = write(dxl::address::kBusWatchdog, off);
  if (r == dxl::BusResult::kIoError) return port_failed("bus watchdog");
  if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) return fail("cannot clear the bus watchdog");
  r = write(dxl::address::kTorqueEnable, off);
  if (r == dxl::BusResult::kIoError) return port_failed("torque off");
  if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) return fail("cannot switch the torque off");
  // The Operating Mode is in EEPROM (limited write cycles): written only when it differs.
  const std::uint8_t wanted =
      s.steering ? dxl::operating_mode::kExtendedPosition : dxl::operating_mode::kVelocity;
  std::uint8_t mode[1] = {0xFF};
  r = read(dxl::address::kOperatingMode, mode);
  if (r == dxl::BusResult::kIoError) return port_failed("operating mode");
  if (r != dxl::BusResult::kOk || (error & 0x7F) != 0)
    return fail("cannot read the operating mode");
  if (mode[0] != wanted) {
    const std::uint8_t set[] = {wanted};
    r = write(dxl::address::kOperatingMode, set);
    if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) {
      return fail("cannot set the operating mode");
    }
  }
  std::uint8_t limit[4] = {};
  r = read(dxl::address::kVelocityLimit, limit);
  if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) {
    return fail("cannot read the Velocity Limit");
  }
  s.velocity_limit = dxl::get_i32(limit, 0);
  if (s.steering) {
    // e-Manual "Min/Max Position Limit(48, 52)": not used in extended position mode. A
    // servo set up to stay within them would not: say so.
    std::uint8_t limits[8] = {};
    r = read(dxl::address::kMaxPositionLimit, limits);
    if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) {
      return fail("cannot read the position limits");
    }
    const std::int32_t max_counts = dxl::get_i32(limits, 0);
    const std::int32_t min_counts = dxl::get_i32(limits, 4);
    if (min_counts > 0 || max_counts < 4095) {
      spdlog::warn(
          "dynamixel ID {} ({}): Min/Max Position Limit {}..{} are not applied by the servo in "
          "extended position mode: the steering is not kept within them",
          s.id, s.name, min_counts, max_counts);
    }
  }
  std::uint8_t present[4] = {};
  r = read(dxl::address::kPresentPosition, present);
  if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) {
    return fail("cannot read the present position");
  }
  reading_.position[i] = dxl::get_i32(present, 0);
  reading_.velocity[i] = 0;
  spdlog::info("dynamixel ID {} ({}): {} (model {}), Velocity Limit {} ({:.2f} rad/s at the {})",
               s.id, s.name, model_name(s.model), s.model, s.velocity_limit,
               s.velocity_limit * kRadpsPerUnit / s.gear_ratio, s.steering ? "steering" : "wheel");
  return true;
}

bool DynamixelHardware::check_velocity_limits() {
  for (std::size_t i = 0; i < servos_.size(); ++i) {
    const Servo& s = servos_[i];
    const double limit_radps = s.velocity_limit * kRadpsPerUnit / s.gear_ratio;
    const double wanted_radps = s.steering ? max_steer_rate_radps_ : max_wheel_rate_radps_;
    const std::string& key = s.steering ? max_steer_rate_key_ : max_wheel_rate_key_;
    // Goals within the limit, whatever the drivetrain asks (the servo ignores one beyond it).
    goal_limit_[i] = s.velocity_limit;
    if (!(wanted_radps > limit_radps)) continue;
    char text[400];
    std::snprintf(text, sizeof text,
                  "dynamixel ID %u (%s): Velocity Limit %d (%.2f rad/s at the %s) is below %s "
                  "= %g rad/s",
                  s.id, s.name.c_str(), s.velocity_limit, limit_radps,
                  s.steering ? "steering" : "wheel", key.c_str(), wanted_radps);
    if (!clamp_to_velocity_limit_ || s.steering) {
      activate_error_ =
          std::string(text) + (s.steering ? ": lower the rate, or raise the servo's limit"
                                          : ": lower the rate, raise the servo's limit, or set "
                                            "over_velocity_limit: clamp");
      return false;
    }
    spdlog::warn("{}: wheel goals are clamped to it (over_velocity_limit: clamp)", text);
  }
  return true;
}

bool DynamixelHardware::arm_watchdogs(dxl::Bus& bus) {
  if (watchdog_units_ == 0) {
    spdlog::warn(
        "dynamixel: bus watchdog off (bus_watchdog_s: 0): the servos keep their last "
        "goals if the daemon dies");
    return true;
  }
  for (const Servo& s : servos_) {
    const std::uint8_t units[] = {watchdog_units_};
    std::uint8_t error = 0;
    const dxl::BusResult r = with_retries(
        [&] { return bus.write(s.id, dxl::address::kBusWatchdog, units, kSetupTimeoutS, error); });
    if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) {
      activate_error_ = format("dynamixel ID %u (%s): %s", s.id, s.name,
                               "cannot arm the bus watchdog (address 98)");
      return false;
    }
  }
  return true;
}

Status DynamixelHardware::activate() {
  stop_thread();
  hold_.store(false, std::memory_order_release);
  // Always from a fresh descriptor: after an unplugged adapter the old one stays dead even
  // once the device is back (a clear re-runs the whole activation on the new one).
  port_.close();
  try {
    port_.open(port_path_, baud_);
  } catch (const std::system_error& e) {
    activate_error_ = std::string("dynamixel: ") + e.what();
    last_error_ = activate_error_.c_str();
    return Status::kError;
  }
  if (const std::string warning = latency_timer_warning(port_path_); !warning.empty()) {
    spdlog::warn("{}", warning);
  }
  dxl::Bus bus(port_);
  reading_ = Reading{};
  auto refuse = [&] {
    last_error_ = activate_error_.c_str();
    return Status::kError;
  };
  for (std::size_t i = 0; i < servos_.size(); ++i) {
    if (!setup_servo(bus, i)) return refuse();
  }
  if (!check_velocity_limits()) return refuse();
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
    activate_error_ = "dynamixel: " + port_path_ + ": port error (cannot write)";
    return refuse();
  }
  for (const Servo& s : servos_) {
    const std::uint8_t on[] = {1};
    std::uint8_t error = 0;
    const dxl::BusResult r = with_retries(
        [&] { return bus.write(s.id, dxl::address::kTorqueEnable, on, kSetupTimeoutS, error); });
    if (r != dxl::BusResult::kOk || (error & 0x7F) != 0) {
      const std::string refusal =
          format("dynamixel ID %u (%s): %s", s.id, s.name, "refuses to switch the torque on");
      deactivate();
      activate_error_ = refusal;
      return refuse();
    }
  }
  // Armed last, just before the bus thread starts feeding it.
  if (!arm_watchdogs(bus)) {
    const std::string error = activate_error_;
    deactivate();
    activate_error_ = error;
    return refuse();
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
  reading_.servo_sample_s.fill(reading_.stamp_s);
  reading_.steer_goal_rad = start_steer_rad_;
  reading_.goal_s = reading_.stamp_s;
  commanded_steer_rate_.fill(0.0);
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
  bool sent = wheel_ids_.empty() || bus.sync_write(dxl::address::kGoalVelocity, 4, wheel_ids_,
                                                   {zero.data(), 4 * wheel_ids_.size()});
  // The watchdog disarmed (it watches only while the torque is on), then the torque off.
  sent = bus.sync_write(dxl::address::kBusWatchdog, 1, all_ids_, {zero.data(), all_ids_.size()}) &&
         sent;
  sent = bus.sync_write(dxl::address::kTorqueEnable, 1, all_ids_, {zero.data(), all_ids_.size()}) &&
         sent;
  // Confirm with each servo; one that does not answer is named (the port, when it failed).
  Status status = Status::kOk;
  for (const Servo& s : servos_) {
    std::uint8_t torque[1] = {1};
    std::uint8_t error = 0;
    const dxl::BusResult r = with_retries(
        [&] { return bus.read(s.id, dxl::address::kTorqueEnable, torque, kSetupTimeoutS, error); });
    if (r == dxl::BusResult::kOk && torque[0] == 0) continue;
    if (status == Status::kOk) {
      activate_error_ =
          !sent || r == dxl::BusResult::kIoError
              ? "dynamixel: " + port_path_ + ": port error: torque off not confirmed"
              : format("dynamixel ID %u (%s): %s", s.id, s.name, "torque off not confirmed");
      last_error_ = activate_error_.c_str();
    }
    status = Status::kError;
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
  ExchangeFloor quickest(kExchangeFloorBlockS);
  // A cycle that starts this long after the last one may have let the servos' watchdogs
  // expire: their Bus Watchdog is read back then, and every kWatchdogReadbackS anyway.
  const double watchdog_check_s = watchdog_units_ > 0 ? 0.5 * bus_watchdog_s_ : 1e300;
  double watchdog_readback_s = watchdog_units_ > 0 ? last_s + kWatchdogReadbackS : 1e300;
  while (!stop_.load(std::memory_order_acquire)) {
    const double start_s = swivel::monotonic_s();
    bool late = start_s - last_s > watchdog_check_s;
    if (start_s >= watchdog_readback_s) {
      late = true;
      watchdog_readback_s = start_s + kWatchdogReadbackS;
    }
    const double dt = std::clamp(start_s - last_s, 0.0, 0.1);
    last_s = start_s;
    commands_.take(command);
    const bool hold = hold_.load(std::memory_order_acquire) || r.fault != FaultKind::kNone;
    for (std::size_t k = 0; k < wheel_index_.size(); ++k) {
      const std::size_t i = wheel_index_[k];
      const std::uint32_t m = servos_[i].module;
      const bool still = hold || command.mode[m] == ModuleDriveMode::kLocked;
      std::int32_t goal = wheel_goal(i, still ? 0.0 : command.wheel_rate_radps[m]);
      // A goal beyond the Velocity Limit would be ignored by the servo: clamped (configured
      // so), else a fault and the wheels stopped.
      if (goal > goal_limit_[i] || goal < -goal_limit_[i]) {
        if (!clamp_to_velocity_limit_ && r.fault == FaultKind::kNone) {
          r.fault = FaultKind::kVelocityLimit;
          r.fault_servo = static_cast<std::uint8_t>(i);
        }
        goal = clamp_to_velocity_limit_ ? std::clamp(goal, -goal_limit_[i], goal_limit_[i]) : 0;
      }
      dxl::put_u32(&data[4 * k], static_cast<std::uint32_t>(goal));
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
    r.steer_goal_rad = steer_target;
    r.goal_s = request_s;
    ok = ok && bus.sync_read(dxl::address::kPresentVelocity, 8, ids, replies, reply_timeout_s_);
    if (!ok && r.fault == FaultKind::kNone) r.fault = FaultKind::kPort;
    const double end_s = swivel::monotonic_s();
    // A servo samples its present values when it takes the request and the last status
    // arrives after all of them crossed the wire: the sample is that wire time before the
    // end (a late start, on a busy host or device, then does not skew it).
    const double sample_s = std::max(request_s, end_s - status_wire_s);
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
          r.servo_sample_s[i] = sample_s;
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
    if (ok && late && r.fault == FaultKind::kNone) {  // also every kWatchdogReadbackS
      // Goals written to a servo whose watchdog expired are refused without a word (a Sync
      // Write has no status): ask each.
      std::array<dxl::SyncReply, kMaxServos> watchdog{};
      if (bus.sync_read(dxl::address::kBusWatchdog, 1, ids, watchdog, reply_timeout_s_)) {
        for (std::size_t i = 0; i < ids.size(); ++i) {
          if (watchdog[i].result == dxl::BusResult::kOk &&
              watchdog[i].data[0] == dxl::kBusWatchdogExpired) {
            r.fault = FaultKind::kWatchdog;
            r.fault_servo = static_cast<std::uint8_t>(i);
            break;
          }
        }
      }
    }
    ++r.cycle;
    r.stamp_s = end_s;
    r.sample_s = sample_s;
    // A late end (the thread woke late for the replies, or the device answered late) moves
    // the estimate away from the true instant by as much: such a reading has no known
    // sampling time, and the loop keeps extrapolating the last one that had. "Late" against
    // the quickest exchange of the last 0.25-0.5 s, so that a lasting change of latency is
    // learnt instead of leaving every later reading untimed.
    const double exchange_s = end_s - request_s;
    if (ok) quickest.add(end_s, exchange_s);
    r.sample_time_known = exchange_s <= quickest.value() + kSampleTimingSlackS;
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
  out.stamp_s = stamp_s;
  out.module_count = module_count_;
  for (std::uint32_t m = 0; m < module_count_; ++m) {
    out.wheel_angle_rad[m] = angle_at(wheel_servo_[m], stamp_s);
    out.steer_angle_rad[m] = steer_angle_at(m, stamp_s);
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
  for (std::uint32_t m = 0; m < command.module_count; ++m) {
    commanded_steer_rate_[m] =
        command.mode[m] == ModuleDriveMode::kLocked ? 0.0 : command.steer_rate_radps[m];
  }
  commands_.publish(command);
  return Status::kOk;
}

}  // namespace swivel::plugins

#ifndef SWIVEL_DYNAMIXEL_NO_EXPORT
SWIVEL_EXPORT_PLUGIN(swivel::plugins::DynamixelHardware, swivel::Hardware, "dynamixel")
#endif
