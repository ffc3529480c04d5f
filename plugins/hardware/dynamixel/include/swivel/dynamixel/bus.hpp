// SPDX-License-Identifier: Apache-2.0
#pragma once
// Transactions on a Protocol 2.0 bus: an instruction out, the status packet(s) back within a
// timeout. Not real-time (it waits on the port); run by the plugin's bus thread and off the
// loop. Does not allocate after construction.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "swivel/dynamixel/protocol.hpp"
#include "swivel/dynamixel/serial_port.hpp"

namespace swivel::dynamixel {

enum class BusResult : std::uint8_t {
  kOk,        ///< status packet received (its error byte may still be non-zero)
  kTimeout,   ///< no status packet from that ID in time
  kCrcError,  ///< a status packet arrived with a bad CRC
  kIoError,   ///< the port failed
  kBadReply,  ///< a status packet of the wrong size
};
const char* bus_result_text(BusResult result) noexcept;

/// Reply of one servo to a Sync Read.
struct SyncReply {
  static constexpr std::size_t kMaxData = 32;
  BusResult result = BusResult::kTimeout;
  std::uint8_t error = 0;  ///< the status error byte
  std::array<std::uint8_t, kMaxData> data{};
};

class Bus {
 public:
  explicit Bus(SerialPort& port) noexcept : port_(port) {}

  /// `model` (when given) receives the model number the status carries.
  BusResult ping(std::uint8_t id, double timeout_s, std::uint8_t& error,
                 std::uint16_t* model = nullptr) noexcept;
  /// Reads `out.size()` bytes from `address`.
  BusResult read(std::uint8_t id, std::uint16_t address, std::span<std::uint8_t> out,
                 double timeout_s, std::uint8_t& error) noexcept;
  BusResult write(std::uint8_t id, std::uint16_t address, std::span<const std::uint8_t> data,
                  double timeout_s, std::uint8_t& error) noexcept;
  /// No reply is expected. False when the packet could not be built or sent.
  bool sync_write(std::uint16_t address, std::uint16_t length, std::span<const std::uint8_t> ids,
                  std::span<const std::uint8_t> data) noexcept;
  /// One reply per ID into `out` (same order); all of them must arrive within `timeout_s`
  /// of the request. False when the request could not be sent.
  bool sync_read(std::uint16_t address, std::uint16_t length, std::span<const std::uint8_t> ids,
                 std::span<SyncReply> out, double timeout_s) noexcept;

  /// Status packets dropped for a bad CRC since construction.
  [[nodiscard]] std::uint64_t crc_errors() const noexcept { return crc_errors_; }

 private:
  BusResult send(std::span<const std::uint8_t> wire) noexcept;
  // Waits for the status packet of `id` until `deadline_s` (CLOCK_MONOTONIC).
  BusResult receive(std::uint8_t id, double deadline_s) noexcept;

  SerialPort& port_;
  Parser parser_;
  std::array<std::uint8_t, 256> rx_{};
  std::size_t rx_begin_ = 0;
  std::size_t rx_end_ = 0;
  std::uint64_t crc_errors_ = 0;
};

}  // namespace swivel::dynamixel
