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
  termios raw{};
  cfmakeraw(&raw);
  char name[256] = {};
  if (openpty(&master_, &slave_, name, &raw, nullptr) != 0) {
    throw std::system_error(errno, std::generic_category(), "emulator: openpty");
  }
  port_ = name;
  fcntl(master_, F_SETFL, fcntl(master_, F_GETFL) | O_NONBLOCK);
  termios master_tio{};
  tcgetattr(master_, &master_tio);
  cfmakeraw(&master_tio);
  tcsetattr(master_, TCSANOW, &master_tio);
  for (const std::uint8_t id : options_.ids) {
    if (id > kMaxId) throw std::invalid_argument("emulator: ID above 252");
    Servo& s = servos_[id];
    s.table[0] = static_cast<std::uint8_t>(options_.model_number);
    s.table[1] = static_cast<std::uint8_t>(options_.model_number >> 8);
    s.table[6] = 45;  // firmware
    s.table[7] = id;
    s.table[address::kOperatingMode] = 3;  // position mode, the factory default
  }
  last_advance_s_ = monotonic_s();
  thread_ = std::thread([this] { serve(); });
}

Emulator::~Emulator() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  if (master_ >= 0) ::close(master_);
  if (slave_ >= 0) ::close(slave_);
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

// Motors move under their goals from the last advance to `now_s`.
void Emulator::advance(double now_s) {
  if (now_s <= last_advance_s_) return;
  const double dt = now_s - last_advance_s_;
  last_advance_s_ = now_s;
  constexpr double kCountsPerUnitS = kVelocityUnitRpm / 60.0 * kPositionCountsPerRev;
  for (auto& [id, s] : servos_) {
    double rate_counts_s = 0.0;
    if (s.table[address::kTorqueEnable] != 0) {
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
    pollfd p{master_, POLLIN, 0};
    if (poll(&p, 1, 10) <= 0) continue;
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
  while (done < wire.size()) {
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
  const bool torque = address <= address::kTorqueEnable && address::kTorqueEnable < address + size;
  if (torque) {
    const std::uint8_t value = data[address::kTorqueEnable - address];
    torque_writes_.push_back({id, value, now_s});
    // A servo in hardware error keeps its torque off.
    if (value != 0 && s.table[address::kHardwareErrorStatus] != 0) {
      error = static_cast<std::uint8_t>(ErrorNumber::kResultFail);
      return;
    }
  }
  // Goal Position in extended mode: the motor starts from where it is.
  std::memcpy(&s.table[address], data, size);
}

void Emulator::handle(const Packet& request, std::size_t request_bytes, double received_s) {
  std::lock_guard lock(mutex_);
  advance(received_s);
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
