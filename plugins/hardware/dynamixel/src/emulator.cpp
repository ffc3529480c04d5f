// SPDX-License-Identifier: Apache-2.0
#include "swivel/dynamixel/emulator.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <pty.h>
#include <sched.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include "swivel/clock.hpp"
#include "swivel/dynamixel/bus.hpp"

namespace swivel::dynamixel {
namespace {

void put(std::array<std::uint8_t, 256>& table, std::uint16_t address, std::int32_t value) {
  put_u32(&table[address], static_cast<std::uint32_t>(value));
}
std::int32_t get(const std::array<std::uint8_t, 256>& table, std::uint16_t address) {
  return get_i32(std::span<const std::uint8_t>(table), address);
}

void sleep_until(double t_s) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_s);
  ts.tv_nsec = static_cast<long>((t_s - static_cast<double>(ts.tv_sec)) * 1e9);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

Emulator::Emulator(Options options) : options_(std::move(options)) {
  const double now_s = monotonic_s();
  for (const std::uint8_t id : options_.ids) {
    if (id > kMaxId) throw std::invalid_argument("emulator: ID above 252");
    Servo& s = servos_[id];
    s.table[0] = static_cast<std::uint8_t>(options_.model_number);
    s.table[1] = static_cast<std::uint8_t>(options_.model_number >> 8);
    s.table[6] = 45;  // firmware
    s.table[7] = id;
    s.table[address::kOperatingMode] = 3;  // position mode, the factory default
    put(s.table, address::kVelocityLimit, kDefaultVelocityLimit);
    put(s.table, address::kMaxPositionLimit, 4095);  // factory defaults: one whole turn
    put(s.table, address::kMinPositionLimit, 0);
    s.last_instruction_s = now_s;
  }
  open_pty();
  last_advance_s_ = now_s;
  thread_ = std::thread([this] { serve(); });
}

Emulator::~Emulator() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  close_pty();
}

void Emulator::open_pty() {
  termios raw{};
  cfmakeraw(&raw);
  char name[256] = {};
  int master = -1;
  int slave = -1;
  if (openpty(&master, &slave, name, &raw, nullptr) != 0) {
    throw std::system_error(errno, std::generic_category(), "emulator: openpty");
  }
  fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK);
  // Not inherited by a process the test starts (swiveld): a copy of the master there would
  // keep the pty alive after disconnect().
  fcntl(master, F_SETFD, FD_CLOEXEC);
  fcntl(slave, F_SETFD, FD_CLOEXEC);
  termios master_tio{};
  tcgetattr(master, &master_tio);
  cfmakeraw(&master_tio);
  tcsetattr(master, TCSANOW, &master_tio);
  std::lock_guard lock(mutex_);
  master_ = master;
  slave_ = slave;
  port_ = name;
}

void Emulator::close_pty() noexcept {
  if (master_ >= 0) ::close(master_);
  if (slave_ >= 0) ::close(slave_);
  master_ = -1;
  slave_ = -1;
}

std::string Emulator::port() const {
  std::lock_guard lock(mutex_);
  return port_;
}

void Emulator::disconnect() {
  port_request_.store(PortRequest::kDisconnect);
  while (port_request_.load() != PortRequest::kNone) usleep(500);
}

void Emulator::reconnect() {
  port_request_.store(PortRequest::kReconnect);
  while (port_request_.load() != PortRequest::kNone) usleep(500);
}

Emulator::Servo* Emulator::find(std::uint8_t id) {
  const auto it = servos_.find(id);
  return it == servos_.end() ? nullptr : &it->second;
}

const Emulator::Servo& Emulator::at(std::uint8_t id) const {
  const auto it = servos_.find(id);
  if (it == servos_.end()) throw std::out_of_range("emulator: no servo with that ID");
  return it->second;
}

void Emulator::set_silent(std::uint8_t id, bool silent) {
  std::lock_guard lock(mutex_);
  servos_.at(id).silent = silent;
}
void Emulator::set_corrupt_crc(std::uint8_t id, bool corrupt) {
  std::lock_guard lock(mutex_);
  servos_.at(id).corrupt_crc = corrupt;
}
void Emulator::set_hardware_error(std::uint8_t id, std::uint8_t bits) {
  std::lock_guard lock(mutex_);
  advance(monotonic_s());
  Servo& s = servos_.at(id);
  s.table[address::kHardwareErrorStatus] = bits;
  if (bits != 0) s.table[address::kTorqueEnable] = 0;
}
void Emulator::set_reply_delay(std::uint8_t id, double delay_s) {
  std::lock_guard lock(mutex_);
  servos_.at(id).reply_delay_s = delay_s;
}
void Emulator::expire_bus_watchdog(std::uint8_t id) {
  std::lock_guard lock(mutex_);
  Servo& s = servos_.at(id);
  const std::uint8_t value = s.table[address::kBusWatchdog];
  if (value == 0 || value > kBusWatchdogMax) return;
  const double now_s = monotonic_s();
  advance(now_s);
  s.table[address::kBusWatchdog] = kBusWatchdogExpired;
  watchdog_expiries_.push_back({id, now_s});
}
void Emulator::drop_replies(std::uint8_t id, int count) {
  std::lock_guard lock(mutex_);
  servos_.at(id).drop_replies = count;
}
void Emulator::set_velocity_limit(std::uint8_t id, std::int32_t units) {
  std::lock_guard lock(mutex_);
  put(servos_.at(id).table, address::kVelocityLimit, units);
}
void Emulator::set_position_limits(std::uint8_t id, std::int32_t min_counts,
                                   std::int32_t max_counts) {
  std::lock_guard lock(mutex_);
  Servo& s = servos_.at(id);
  put(s.table, address::kMinPositionLimit, min_counts);
  put(s.table, address::kMaxPositionLimit, max_counts);
}
void Emulator::set_operating_mode(std::uint8_t id, std::uint8_t mode) {
  std::lock_guard lock(mutex_);
  servos_.at(id).table[address::kOperatingMode] = mode;
}
void Emulator::set_present_position(std::uint8_t id, std::int32_t counts) {
  std::lock_guard lock(mutex_);
  Servo& s = servos_.at(id);
  s.position_counts = counts;
  put(s.table, address::kPresentPosition, counts);
}

std::vector<Emulator::TorqueWrite> Emulator::torque_writes() const {
  std::lock_guard lock(mutex_);
  return torque_writes_;
}
std::uint8_t Emulator::torque_enable(std::uint8_t id) const {
  std::lock_guard lock(mutex_);
  return at(id).table[address::kTorqueEnable];
}
std::uint8_t Emulator::operating_mode(std::uint8_t id) const {
  std::lock_guard lock(mutex_);
  return at(id).table[address::kOperatingMode];
}
std::int32_t Emulator::goal_velocity(std::uint8_t id) const {
  std::lock_guard lock(mutex_);
  return get(at(id).table, address::kGoalVelocity);
}
std::int32_t Emulator::goal_position(std::uint8_t id) const {
  std::lock_guard lock(mutex_);
  return get(at(id).table, address::kGoalPosition);
}
std::int32_t Emulator::present_position(std::uint8_t id) const {
  std::lock_guard lock(mutex_);
  return get(at(id).table, address::kPresentPosition);
}

std::int32_t Emulator::present_velocity(std::uint8_t id) {
  std::lock_guard lock(mutex_);
  advance(monotonic_s());
  return get(at(id).table, address::kPresentVelocity);
}
std::uint8_t Emulator::bus_watchdog(std::uint8_t id) const {
  std::lock_guard lock(mutex_);
  return at(id).table[address::kBusWatchdog];
}
std::vector<Emulator::WatchdogExpiry> Emulator::watchdog_expiries() const {
  std::lock_guard lock(mutex_);
  return watchdog_expiries_;
}
int Emulator::eeprom_writes(std::uint8_t id) const {
  std::lock_guard lock(mutex_);
  return at(id).eeprom_writes;
}

// e-Manual, "Bus Watchdog(98)": armed (1-127, unit 20 ms) and the torque on, no instruction
// packet for longer than that stops the servo and sets the value to -1.
void Emulator::check_watchdogs(double now_s) {
  for (auto& [id, s] : servos_) {
    const std::uint8_t value = s.table[address::kBusWatchdog];
    if (value == 0 || value > kBusWatchdogMax || s.table[address::kTorqueEnable] == 0) continue;
    const double expires_s = s.last_instruction_s + value * kBusWatchdogUnitS;
    if (now_s < expires_s) continue;
    advance(expires_s);  // it ran until then
    s.table[address::kBusWatchdog] = kBusWatchdogExpired;
    watchdog_expiries_.push_back({id, expires_s});
  }
}

// Motors move under their goals from the last advance to `now_s`.
void Emulator::advance(double now_s) {
  if (now_s <= last_advance_s_) return;
  const double dt = now_s - last_advance_s_;
  last_advance_s_ = now_s;
  constexpr double kCountsPerUnitS = kVelocityUnitRpm / 60.0 * kPositionCountsPerRev;
  for (auto& [id, s] : servos_) {
    double rate_counts_s = 0.0;
    // A servo whose bus watchdog expired stands (Profile Acceleration and Velocity as 0).
    if (s.table[address::kTorqueEnable] != 0 &&
        s.table[address::kBusWatchdog] != kBusWatchdogExpired) {
      if (s.table[address::kOperatingMode] == operating_mode::kVelocity) {
        rate_counts_s = get(s.table, address::kGoalVelocity) * kCountsPerUnitS;
      } else if (s.table[address::kOperatingMode] == operating_mode::kExtendedPosition &&
                 dt > 0.0) {
        // First-order tracking of the goal (time constant position_time_constant_s), at
        // most max_position_speed_rev_s.
        const double max_step = options_.max_position_speed_rev_s * kPositionCountsPerRev * dt;
        const double error = get(s.table, address::kGoalPosition) - s.position_counts;
        const double step =
            error * (1.0 - std::exp(-dt / std::max(options_.position_time_constant_s, 1e-6)));
        rate_counts_s = std::clamp(step, -max_step, max_step) / dt;
      }
    }
    s.position_counts += rate_counts_s * dt;
    put(s.table, address::kPresentPosition,
        static_cast<std::int32_t>(std::llround(s.position_counts)));
    put(s.table, address::kPresentVelocity,
        static_cast<std::int32_t>(std::lround(rate_counts_s / kCountsPerUnitS)));
  }
}

void Emulator::serve() noexcept {
  if (options_.fifo_priority > 0) {
    sched_param param{};
    param.sched_priority = options_.fifo_priority;
    (void)pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);  // best effort
  }
  Parser parser;
  std::array<std::uint8_t, 512> buffer{};
  std::size_t packet_bytes = 0;
  while (!stop_.load()) {
    const PortRequest request = port_request_.load();
    if (request != PortRequest::kNone) {
      if (request == PortRequest::kDisconnect) {
        std::lock_guard lock(mutex_);
        close_pty();
      } else if (master_ < 0) {
        try {
          open_pty();
        } catch (const std::system_error&) {
          // No pty to be had: stays unplugged.
        }
      }
      parser.reset();
      packet_bytes = 0;
      port_request_.store(PortRequest::kNone);
    }
    if (master_ < 0) {
      usleep(1000);
      std::lock_guard lock(mutex_);
      check_watchdogs(monotonic_s());
      continue;
    }
    // A short poll: the watchdogs are checked while the bus is quiet, to within 2 ms. Not
    // with input pending: a packet that waited for this thread (a loaded test machine) was
    // on the wire in time.
    pollfd p{master_, POLLIN, 0};
    const int ready = poll(&p, 1, 2);
    if (ready == 0) {
      std::lock_guard lock(mutex_);
      check_watchdogs(monotonic_s());
    }
    if (ready <= 0) continue;
    const ssize_t n = ::read(master_, buffer.data(), buffer.size());
    if (n <= 0) {
      if (n < 0 && errno != EAGAIN && errno != EINTR && errno != EIO) return;
      if (n < 0 && errno == EIO) usleep(1000);  // no client has the slave open
      continue;
    }
    const double received_s = monotonic_s();
    std::span<const std::uint8_t> rest(buffer.data(), static_cast<std::size_t>(n));
    while (!rest.empty()) {
      std::size_t used = 0;
      const Parser::Result r = parser.feed(rest, used);
      rest = rest.subspan(used);
      packet_bytes += used;
      if (r == Parser::Result::kNeedMore) continue;
      ++requests_;
      if (options_.baud > 0) {  // every request occupies the wire, answered or not
        std::lock_guard lock(mutex_);
        wire_free_s_ = std::max(wire_free_s_, received_s) +
                       10.0 / options_.baud * static_cast<double>(packet_bytes);
      }
      if (r == Parser::Result::kPacket) {
        try {
          handle(parser.packet(), packet_bytes, received_s);
        } catch (...) {
          // Out of memory in the recorder: drop the request, keep serving.
        }
      } else {
        ++bad_requests_;
      }
      packet_bytes = 0;
    }
  }
}

void Emulator::reply(std::uint8_t id, Servo& servo, std::uint8_t error, const std::uint8_t* data,
                     std::size_t size, std::size_t request_bytes, double received_s) {
  if (servo.silent) return;
  if (servo.drop_replies > 0) {
    --servo.drop_replies;
    return;
  }
  if (servo.table[address::kHardwareErrorStatus] != 0) error |= kAlertBit;
  PacketBuilder b(id, Instruction::kStatus);
  b.u8(error).bytes({data, size});
  std::span<const std::uint8_t> wire = b.finish();
  std::array<std::uint8_t, kMaxPacketBytes> out{};
  std::memcpy(out.data(), wire.data(), wire.size());
  if (servo.corrupt_crc) out[wire.size() - 1] ^= 0x5A;
  // The wire: the request, then each reply in turn, at the emulated rate.
  // (serve() has put the request on the wire already.)
  (void)request_bytes;
  double send_at = received_s + servo.reply_delay_s + options_.return_delay_s;
  if (options_.baud > 0) {
    const double byte_s = 10.0 / options_.baud;
    send_at = std::max(send_at, wire_free_s_ + options_.return_delay_s) +
              byte_s * static_cast<double>(wire.size());
    wire_free_s_ = send_at;
  }
  mutex_.unlock();  // callers hold it; let observers in while waiting
  if (send_at > monotonic_s()) sleep_until(send_at);
  std::size_t done = 0;
  while (master_ >= 0 && done < wire.size()) {
    const ssize_t n = ::write(master_, out.data() + done, wire.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
    } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
      break;
    } else {
      usleep(100);
    }
  }
  mutex_.lock();
}

void Emulator::write_table(std::uint8_t id, Servo& s, std::uint16_t address,
                           const std::uint8_t* data, std::size_t size, double now_s,
                           std::uint8_t& error) {
  error = 0;
  if (address + size > s.table.size()) {
    error = static_cast<std::uint8_t>(ErrorNumber::kDataRangeError);
    return;
  }
  // EEPROM (below 64) is locked while the torque is on.
  if (address < 64 && s.table[address::kTorqueEnable] != 0) {
    error = static_cast<std::uint8_t>(ErrorNumber::kAccessError);
    return;
  }
  auto covers = [&](std::uint16_t at) { return address <= at && at < address + size; };
  if (covers(address::kBusWatchdog)) {
    const std::uint8_t value = data[address::kBusWatchdog - address];
    if (value > kBusWatchdogMax) {  // 0 ~ 127 may be written
      error = static_cast<std::uint8_t>(ErrorNumber::kDataRangeError);
      return;
    }
  }
  // Goal values are read-only after the watchdog expired (e-Manual, "Bus Watchdog(98)").
  if (s.table[address::kBusWatchdog] == kBusWatchdogExpired && address < 120 &&
      address + size > 100 && !covers(address::kBusWatchdog)) {
    error = static_cast<std::uint8_t>(ErrorNumber::kDataRangeError);
    return;
  }
  // Goal Velocity within +-Velocity Limit (e-Manual, "Goal Velocity(104)").
  if (address <= address::kGoalVelocity && address::kGoalVelocity + 4 <= address + size) {
    const std::int32_t goal =
        get_i32({data, size}, static_cast<std::size_t>(address::kGoalVelocity - address));
    const std::int32_t limit = get(s.table, address::kVelocityLimit);
    if (goal > limit || goal < -limit) {
      error = static_cast<std::uint8_t>(ErrorNumber::kDataLimitError);
      return;
    }
  }
  if (covers(address::kTorqueEnable)) {
    const std::uint8_t value = data[address::kTorqueEnable - address];
    torque_writes_.push_back({id, value, now_s});
    // A servo in hardware error keeps its torque off.
    if (value != 0 && s.table[address::kHardwareErrorStatus] != 0) {
      error = static_cast<std::uint8_t>(ErrorNumber::kResultFail);
      return;
    }
  }
  if (address < 64) ++s.eeprom_writes;
  // Goal Position in extended mode: the motor starts from where it is.
  std::memcpy(&s.table[address], data, size);
}

void Emulator::handle(const Packet& request, std::size_t request_bytes, double received_s) {
  std::lock_guard lock(mutex_);
  advance(received_s);
  // Every instruction packet to a servo's ID or to all of them feeds its watchdog.
  for (auto& [id, s] : servos_) {
    if (request.id == id || request.id == kBroadcastId) s.last_instruction_s = received_s;
  }
  const std::span<const std::uint8_t> params(request.params.data(), request.param_count);
  const auto instruction = static_cast<Instruction>(request.instruction);
  switch (instruction) {
    case Instruction::kPing:
    case Instruction::kRead:
    case Instruction::kWrite: {
      Servo* s = find(request.id);
      if (s == nullptr) return;  // no such servo (broadcast not served for these)
      std::uint8_t error = 0;
      if (instruction == Instruction::kPing) {
        const std::uint8_t data[] = {s->table[0], s->table[1], s->table[6]};
        reply(request.id, *s, 0, data, 3, request_bytes, received_s);
      } else if (instruction == Instruction::kRead) {
        if (params.size() != 4) {
          reply(request.id, *s, static_cast<std::uint8_t>(ErrorNumber::kDataLengthError), nullptr,
                0, request_bytes, received_s);
          return;
        }
        const std::uint16_t address = get_u16(params, 0);
        const std::uint16_t length = get_u16(params, 2);
        if (address + length > s->table.size()) {
          reply(request.id, *s, static_cast<std::uint8_t>(ErrorNumber::kDataRangeError), nullptr, 0,
                request_bytes, received_s);
          return;
        }
        const std::array<std::uint8_t, 256> copy = s->table;
        reply(request.id, *s, 0, copy.data() + address, length, request_bytes, received_s);
      } else {
        if (params.size() < 3) {
          reply(request.id, *s, static_cast<std::uint8_t>(ErrorNumber::kDataLengthError), nullptr,
                0, request_bytes, received_s);
          return;
        }
        write_table(request.id, *s, get_u16(params, 0), params.data() + 2, params.size() - 2,
                    received_s, error);
        reply(request.id, *s, error, nullptr, 0, request_bytes, received_s);
      }
      return;
    }
    case Instruction::kSyncRead: {
      if (params.size() < 5) return;
      const std::uint16_t address = get_u16(params, 0);
      const std::uint16_t length = get_u16(params, 2);
      if (address + length > 256) return;
      for (std::size_t i = 4; i < params.size(); ++i) {
        Servo* s = find(params[i]);
        if (s == nullptr) continue;
        const std::array<std::uint8_t, 256> copy = s->table;
        reply(params[i], *s, 0, copy.data() + address, length, request_bytes, received_s);
      }
      return;
    }
    case Instruction::kSyncWrite: {
      if (params.size() < 4) return;
      const std::uint16_t address = get_u16(params, 0);
      const std::uint16_t length = get_u16(params, 2);
      for (std::size_t at = 4; at + 1 + length <= params.size(); at += 1 + length) {
        Servo* s = find(params[at]);
        if (s == nullptr || s->silent) continue;
        std::uint8_t error = 0;
        write_table(params[at], *s, address, params.data() + at + 1, length, received_s, error);
      }
      return;
    }
    case Instruction::kStatus: return;
  }
  // Unknown instruction: the addressed servo says so.
  if (Servo* s = find(request.id)) {
    reply(request.id, *s, static_cast<std::uint8_t>(ErrorNumber::kInstructionError), nullptr, 0,
          request_bytes, received_s);
  }
}

}  // namespace swivel::dynamixel
