// SPDX-License-Identifier: Apache-2.0
#pragma once
// A DYNAMIXEL X-series bus emulated on a pseudo-terminal, for tests and benches: open
// port() with SerialPort (or point a `dynamixel` plugin at it) and talk Protocol 2.0.
//
// It serves PING, READ, WRITE, SYNC_READ and SYNC_WRITE for several IDs, each with a
// control table of 256 bytes. Motors follow Goal Velocity (operating mode 1) or Goal
// Position (mode 4, first order, at up to max_position_speed_rev_s) while Torque Enable is 1;
// writing the Operating Mode with the torque on is refused (access error), as on the servos.
// Injectable faults per ID: silence (no status packets), corrupt CRC (replies with a wrong
// CRC), hardware error bits (Hardware Error Status set, the alert bit in every status, the
// torque switched off, as the servos do) and slow replies. Every Torque Enable write is
// recorded.
//
// Not real-time: a thread with a mutex. The wire can be timed: with `baud` > 0 each reply
// leaves no earlier than the time the request and the reply take on a wire at that rate.

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "swivel/dynamixel/protocol.hpp"

namespace swivel::dynamixel {

class Emulator {
 public:
  struct Options {
    std::vector<std::uint8_t> ids{1, 2};
    std::uint32_t baud = 0;                  ///< 0: replies as fast as the pty carries them
    double return_delay_s = 0.0;             ///< per status packet, like Return Delay Time
    double max_position_speed_rev_s = 2.0;   ///< position mode: top speed (motor side)
    double position_time_constant_s = 0.01;  ///< position mode: first-order tracking
    std::uint16_t model_number = 1020;       ///< XM430-W350
    int fifo_priority = 0;  ///< > 0: serve on SCHED_FIFO at this priority where permitted
  };
  struct TorqueWrite {
    std::uint8_t id = 0;
    std::uint8_t value = 0;
    double time_s = 0.0;  ///< CLOCK_MONOTONIC
  };

  /// Opens the pseudo-terminal and starts serving. @throws std::system_error.
  explicit Emulator(Options options);
  ~Emulator();
  Emulator(const Emulator&) = delete;
  Emulator& operator=(const Emulator&) = delete;

  /// The device path to open (the pty's slave side).
  [[nodiscard]] const std::string& port() const noexcept { return port_; }

  // Faults, from any thread, in effect from the next request.
  void set_silent(std::uint8_t id, bool silent);
  void set_corrupt_crc(std::uint8_t id, bool corrupt);
  /// Sets Hardware Error Status to `bits` (0 clears it); non-zero also turns the torque off.
  void set_hardware_error(std::uint8_t id, std::uint8_t bits);
  void set_reply_delay(std::uint8_t id, double delay_s);

  // Observations.
  [[nodiscard]] std::vector<TorqueWrite> torque_writes() const;
  [[nodiscard]] std::uint8_t torque_enable(std::uint8_t id) const;
  [[nodiscard]] std::uint8_t operating_mode(std::uint8_t id) const;
  [[nodiscard]] std::int32_t goal_velocity(std::uint8_t id) const;
  [[nodiscard]] std::int32_t goal_position(std::uint8_t id) const;
  [[nodiscard]] std::int32_t present_position(std::uint8_t id) const;
  /// Instruction packets received (any ID) and how many had a bad CRC.
  [[nodiscard]] std::uint64_t requests() const noexcept { return requests_.load(); }
  [[nodiscard]] std::uint64_t bad_requests() const noexcept { return bad_requests_.load(); }
  /// Sets a servo's present position (motor counts), e.g. a non-zero start.
  void set_present_position(std::uint8_t id, std::int32_t counts);

 private:
  struct Servo {
    std::array<std::uint8_t, 256> table{};
    double position_counts = 0.0;
    bool silent = false;
    bool corrupt_crc = false;
    double reply_delay_s = 0.0;
  };

  void serve() noexcept;
  void handle(const Packet& request, std::size_t request_bytes, double received_s);
  void advance(double now_s);
  void write_table(std::uint8_t id, Servo& servo, std::uint16_t address, const std::uint8_t* data,
                   std::size_t size, double now_s, std::uint8_t& error);
  void reply(std::uint8_t id, Servo& servo, std::uint8_t error, const std::uint8_t* data,
             std::size_t size, std::size_t request_bytes, double received_s);
  Servo* find(std::uint8_t id);
  const Servo& at(std::uint8_t id) const;

  Options options_;
  int master_ = -1;
  int slave_ = -1;  // kept open so that the pty survives clients closing it
  std::string port_;
  mutable std::mutex mutex_;
  std::map<std::uint8_t, Servo> servos_;
  std::vector<TorqueWrite> torque_writes_;
  double last_advance_s_ = 0.0;
  double wire_free_s_ = 0.0;  // when the emulated wire is next idle
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> requests_{0};
  std::atomic<std::uint64_t> bad_requests_{0};
  std::thread thread_;
};

}  // namespace swivel::dynamixel
