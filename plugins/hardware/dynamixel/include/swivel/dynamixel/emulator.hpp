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
// CRC), a number of status packets dropped, hardware error bits (Hardware Error Status set,
// the alert bit in every status, the torque switched off, as the servos do) and slow
// replies; for the whole bus, an adapter unplugged and plugged back in (the pty closed, a
// new one opened). Every Torque Enable write is recorded, and so are EEPROM writes.
//
// As the ROBOTIS e-Manual specifies for the X-series (XM430-W350 control table, "Bus
// Watchdog(98)", "Velocity Limit(44)", "Min/Max Position Limit(48, 52)"):
// - Bus Watchdog (98, 1 byte, unit 20 ms; 0 disables and clears its error, 1-127 arms it):
//   while the torque is on, a servo that receives no instruction packet for longer than the
//   set time stops (Profile Acceleration and Velocity applied as 0: at once), the value
//   becomes -1 (0xFF) and Goal PWM, Current, Velocity and Position (100-119) turn read-only:
//   a write to them is answered with a range error until 0 is written to 98. Every packet
//   addressed to the servo's ID or to the broadcast ID (Sync Read and Sync Write) counts.
// - Velocity Limit (44, 4 bytes, 0.229 rpm, EEPROM): a Goal Velocity beyond it is refused
//   (data limit error; a Sync Write gets no status, so it is dropped silently).
// - Min/Max Position Limit (52, 48; EEPROM): held in the table only (the servos do not use
//   them in extended position mode).
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
  struct WatchdogExpiry {
    std::uint8_t id = 0;
    double time_s = 0.0;  ///< CLOCK_MONOTONIC: last instruction + the watchdog time
  };
  /// Velocity Limit (44) of each servo at start: 1023 (234 rpm), the top of its range
  /// (e-Manual, "Velocity Limit(44)": 0 ~ 1,023), so that no goal of a test is beyond it
  /// unless set_velocity_limit() says so. (An XM430-W350 leaves the factory with 200.)
  static constexpr std::int32_t kDefaultVelocityLimit = 1023;

  /// Opens the pseudo-terminal and starts serving. @throws std::system_error.
  explicit Emulator(Options options);
  ~Emulator();
  Emulator(const Emulator&) = delete;
  Emulator& operator=(const Emulator&) = delete;

  /// The device path to open (the pty's slave side); a new one after reconnect().
  [[nodiscard]] std::string port() const;

  /// The adapter unplugged: the pty closes (its clients read an error) and no servo hears
  /// anything (their watchdogs run out). Returns once done.
  void disconnect();
  /// Plugged back in: a new pty (see port()). Returns once serving it.
  void reconnect();

  // Faults, from any thread, in effect from the next request.
  void set_silent(std::uint8_t id, bool silent);
  void set_corrupt_crc(std::uint8_t id, bool corrupt);
  /// Sets Hardware Error Status to `bits` (0 clears it); non-zero also turns the torque off.
  void set_hardware_error(std::uint8_t id, std::uint8_t bits);
  void set_reply_delay(std::uint8_t id, double delay_s);
  /// An armed Bus Watchdog of `id` expires now, as if the servo had missed the bus's packets
  /// for its time (the servo stops; its goals turn read-only).
  void expire_bus_watchdog(std::uint8_t id);
  /// The next `count` status packets of `id` are not sent (a transient loss).
  void drop_replies(std::uint8_t id, int count);
  /// EEPROM settings, as if written with a configuration tool before.
  void set_velocity_limit(std::uint8_t id, std::int32_t units);
  void set_position_limits(std::uint8_t id, std::int32_t min_counts, std::int32_t max_counts);
  void set_operating_mode(std::uint8_t id, std::uint8_t mode);

  // Observations.
  [[nodiscard]] std::vector<TorqueWrite> torque_writes() const;
  [[nodiscard]] std::uint8_t torque_enable(std::uint8_t id) const;
  [[nodiscard]] std::uint8_t operating_mode(std::uint8_t id) const;
  [[nodiscard]] std::int32_t goal_velocity(std::uint8_t id) const;
  [[nodiscard]] std::int32_t goal_position(std::uint8_t id) const;
  [[nodiscard]] std::int32_t present_position(std::uint8_t id) const;
  /// Present Velocity (0.229 rpm units) as of now (the motors advanced to this instant).
  [[nodiscard]] std::int32_t present_velocity(std::uint8_t id);
  /// Bus Watchdog (98): 0 off, 1-127 armed, 0xFF expired.
  [[nodiscard]] std::uint8_t bus_watchdog(std::uint8_t id) const;
  [[nodiscard]] std::vector<WatchdogExpiry> watchdog_expiries() const;
  /// Writes to EEPROM addresses (below 64) that `id` accepted.
  [[nodiscard]] int eeprom_writes(std::uint8_t id) const;
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
    int drop_replies = 0;
    int eeprom_writes = 0;
    double last_instruction_s = 0.0;  // the Bus Watchdog's reference
  };

  void serve() noexcept;
  void check_watchdogs(double now_s);
  void open_pty();
  void close_pty() noexcept;
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
  std::vector<WatchdogExpiry> watchdog_expiries_;
  // disconnect()/reconnect() ask the serving thread, the only one touching the descriptors.
  enum class PortRequest : int { kNone, kDisconnect, kReconnect };
  std::atomic<PortRequest> port_request_{PortRequest::kNone};
  double last_advance_s_ = 0.0;
  double wire_free_s_ = 0.0;  // when the emulated wire is next idle
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> requests_{0};
  std::atomic<std::uint64_t> bad_requests_{0};
  std::thread thread_;
};

}  // namespace swivel::dynamixel
