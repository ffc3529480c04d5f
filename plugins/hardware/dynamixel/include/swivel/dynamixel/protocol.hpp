// SPDX-License-Identifier: Apache-2.0
#pragma once
// DYNAMIXEL Protocol 2.0: packet framing, CRC, instruction builders and a status-packet
// parser. Plain code: no I/O, no allocation, no exceptions; every function is real-time safe.
//
// Packet: 0xFF 0xFF 0xFD 0x00 | ID | LEN_L LEN_H | INST | params... | CRC_L CRC_H
//   LEN counts INST, the (stuffed) params and the two CRC bytes. Inside INST..params any
//   0xFF 0xFF 0xFD gets an extra 0xFD (byte stuffing) so that it never reads as a header.
//   The CRC (CRC-16, polynomial 0x8005, initial value 0, no reflection) covers everything
//   from the first header byte to the last (stuffed) parameter.
// Status packet: INST = 0x55, first parameter the error byte (bit 7 = hardware alert).

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace swivel::dynamixel {

inline constexpr std::uint8_t kBroadcastId = 0xFE;
inline constexpr std::uint8_t kMaxId = 0xFC;  ///< highest unicast ID

enum class Instruction : std::uint8_t {
  kPing = 0x01,
  kRead = 0x02,
  kWrite = 0x03,
  kSyncRead = 0x82,
  kSyncWrite = 0x83,
  kStatus = 0x55,
};

/// X-series control table addresses used here (RAM area unless noted), from the ROBOTIS
/// e-Manual's control tables (XM430-W350, XL430-W250: "Control Table of EEPROM Area", "...
/// of RAM Area").
namespace address {
inline constexpr std::uint16_t kModelNumber = 0;           ///< EEPROM, 2 bytes, read-only
inline constexpr std::uint16_t kOperatingMode = 11;        ///< EEPROM, 1 byte
inline constexpr std::uint16_t kVelocityLimit = 44;        ///< EEPROM, 4 bytes, 0.229 rpm
inline constexpr std::uint16_t kMaxPositionLimit = 48;     ///< EEPROM, 4 bytes, single turn
inline constexpr std::uint16_t kMinPositionLimit = 52;     ///< EEPROM, 4 bytes, single turn
inline constexpr std::uint16_t kTorqueEnable = 64;         ///< 1 byte
inline constexpr std::uint16_t kHardwareErrorStatus = 70;  ///< 1 byte
inline constexpr std::uint16_t kBusWatchdog = 98;          ///< 1 byte, unit 20 ms
inline constexpr std::uint16_t kGoalVelocity = 104;        ///< 4 bytes, 0.229 rpm units
inline constexpr std::uint16_t kGoalPosition = 116;        ///< 4 bytes, 4096 per revolution
inline constexpr std::uint16_t kPresentVelocity = 128;     ///< 4 bytes
inline constexpr std::uint16_t kPresentPosition = 132;     ///< 4 bytes
}  // namespace address

namespace operating_mode {
inline constexpr std::uint8_t kVelocity = 1;
inline constexpr std::uint8_t kExtendedPosition = 4;
}  // namespace operating_mode

inline constexpr double kVelocityUnitRpm = 0.229;

/// Bus Watchdog (98), e-Manual "Bus Watchdog(98)": 0 disables it (and clears its error),
/// 1-127 arm it in units of 20 ms; it reads -1 (0xFF) once it expired: the servo stopped and
/// its goal values are read-only until 0 is written.
inline constexpr double kBusWatchdogUnitS = 0.020;
inline constexpr std::uint8_t kBusWatchdogMax = 127;
inline constexpr std::uint8_t kBusWatchdogExpired = 0xFF;
inline constexpr double kPositionCountsPerRev = 4096.0;

/// Status error byte: bit 7 alert (see Hardware Error Status), bits 0-6 the error number.
inline constexpr std::uint8_t kAlertBit = 0x80;
enum class ErrorNumber : std::uint8_t {
  kNone = 0,
  kResultFail = 1,
  kInstructionError = 2,
  kCrcError = 3,
  kDataRangeError = 4,
  kDataLengthError = 5,
  kDataLimitError = 6,
  kAccessError = 7,
};
/// Static text of the error number in a status error byte (the alert bit ignored).
const char* error_number_text(std::uint8_t error) noexcept;

/// Hardware Error Status (address 70) bits.
namespace hardware_error {
inline constexpr std::uint8_t kInputVoltage = 0x01;
inline constexpr std::uint8_t kOverheating = 0x04;
inline constexpr std::uint8_t kMotorEncoder = 0x08;
inline constexpr std::uint8_t kElectricalShock = 0x10;
inline constexpr std::uint8_t kOverload = 0x20;
}  // namespace hardware_error
/// Static text naming the most serious bit set in `status` ("" when none is set):
/// "input voltage error", "overheating", "motor encoder error", "electrical shock",
/// "overload", or "unknown hardware error" for undocumented bits only.
const char* hardware_error_text(std::uint8_t status) noexcept;

/// CRC-16 (poly 0x8005, init `crc`) over `data`; chain calls by passing the previous result.
std::uint16_t crc16(std::span<const std::uint8_t> data, std::uint16_t crc = 0) noexcept;

/// Largest packet this library builds or accepts (header to CRC, stuffed).
inline constexpr std::size_t kMaxPacketBytes = 1024;

/// A packet being built. Parameters are appended unstuffed; finish() stuffs them, writes the
/// length and the CRC. Fixed capacity: an append past it sets overflow() and is dropped.
class PacketBuilder {
 public:
  PacketBuilder(std::uint8_t id, Instruction instruction) noexcept;
  PacketBuilder& u8(std::uint8_t value) noexcept;
  PacketBuilder& u16(std::uint16_t value) noexcept;  ///< little endian
  PacketBuilder& u32(std::uint32_t value) noexcept;  ///< little endian
  PacketBuilder& i32(std::int32_t value) noexcept { return u32(static_cast<std::uint32_t>(value)); }
  PacketBuilder& bytes(std::span<const std::uint8_t> data) noexcept;
  /// The wire bytes (empty on overflow). Call once, after the last parameter.
  std::span<const std::uint8_t> finish() noexcept;
  [[nodiscard]] bool overflow() const noexcept { return overflow_; }

 private:
  std::array<std::uint8_t, kMaxPacketBytes> raw_{};  // INST + params, unstuffed
  std::size_t raw_size_ = 0;
  std::array<std::uint8_t, kMaxPacketBytes> wire_{};
  std::size_t wire_size_ = 0;
  std::uint8_t id_ = 0;
  bool overflow_ = false;
};

// Instruction builders: each returns the finished wire bytes held by `b`.
std::span<const std::uint8_t> build_ping(PacketBuilder& b) noexcept;
std::span<const std::uint8_t> build_read(PacketBuilder& b, std::uint16_t address,
                                         std::uint16_t length) noexcept;
std::span<const std::uint8_t> build_write(PacketBuilder& b, std::uint16_t address,
                                          std::span<const std::uint8_t> data) noexcept;
std::span<const std::uint8_t> build_sync_read(PacketBuilder& b, std::uint16_t address,
                                              std::uint16_t length,
                                              std::span<const std::uint8_t> ids) noexcept;
/// `data` holds ids.size() blocks of `length` bytes, one per ID in order.
std::span<const std::uint8_t> build_sync_write(PacketBuilder& b, std::uint16_t address,
                                               std::uint16_t length,
                                               std::span<const std::uint8_t> ids,
                                               std::span<const std::uint8_t> data) noexcept;

/// A decoded packet (instruction or status), parameters unstuffed.
struct Packet {
  std::uint8_t id = 0;
  std::uint8_t instruction = 0;
  std::array<std::uint8_t, kMaxPacketBytes> params{};
  std::size_t param_count = 0;

  [[nodiscard]] bool is_status() const noexcept {
    return instruction == static_cast<std::uint8_t>(Instruction::kStatus) && param_count >= 1;
  }
  /// Status packets: the error byte and the data after it.
  [[nodiscard]] std::uint8_t error() const noexcept { return param_count > 0 ? params[0] : 0; }
  [[nodiscard]] std::span<const std::uint8_t> data() const noexcept {
    return param_count > 0 ? std::span<const std::uint8_t>(params.data() + 1, param_count - 1)
                           : std::span<const std::uint8_t>();
  }
};

/// Byte-stream decoder: feed() bytes as they arrive; it resynchronises on the header after
/// garbage, and reports each complete packet or a CRC failure.
class Parser {
 public:
  enum class Result : std::uint8_t {
    kNeedMore,   ///< no complete packet yet
    kPacket,     ///< `packet()` holds a packet whose CRC matched
    kCrcError,   ///< a complete packet whose CRC did not match (dropped)
    kBadLength,  ///< a length field below 3 or past kMaxPacketBytes (dropped)
  };
  /// Consumes bytes from `data` up to and including the end of the first packet (or all of
  /// them); `consumed` says how many. Call again with the rest.
  Result feed(std::span<const std::uint8_t> data, std::size_t& consumed) noexcept;
  [[nodiscard]] const Packet& packet() const noexcept { return packet_; }
  /// The ID byte of the last complete packet, kCrcError ones included (a hint only: the
  /// CRC did not vouch for it).
  [[nodiscard]] std::uint8_t last_id() const noexcept { return last_id_; }
  void reset() noexcept { size_ = 0; }

 private:
  Result finish_packet() noexcept;
  std::array<std::uint8_t, kMaxPacketBytes> buffer_{};
  std::size_t size_ = 0;
  std::size_t expected_ = 0;  // total bytes of the current packet once the length is known
  Packet packet_{};
  std::uint8_t last_id_ = 0;
};

/// Little-endian readers for status data.
inline std::uint32_t get_u32(std::span<const std::uint8_t> d, std::size_t at) noexcept {
  return static_cast<std::uint32_t>(d[at]) | (static_cast<std::uint32_t>(d[at + 1]) << 8) |
         (static_cast<std::uint32_t>(d[at + 2]) << 16) |
         (static_cast<std::uint32_t>(d[at + 3]) << 24);
}
inline std::int32_t get_i32(std::span<const std::uint8_t> d, std::size_t at) noexcept {
  return static_cast<std::int32_t>(get_u32(d, at));
}
inline std::uint16_t get_u16(std::span<const std::uint8_t> d, std::size_t at) noexcept {
  return static_cast<std::uint16_t>(d[at] | (d[at + 1] << 8));
}
inline void put_u32(std::uint8_t* out, std::uint32_t v) noexcept {
  out[0] = static_cast<std::uint8_t>(v);
  out[1] = static_cast<std::uint8_t>(v >> 8);
  out[2] = static_cast<std::uint8_t>(v >> 16);
  out[3] = static_cast<std::uint8_t>(v >> 24);
}

}  // namespace swivel::dynamixel
