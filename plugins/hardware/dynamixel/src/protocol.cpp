// SPDX-License-Identifier: Apache-2.0
#include "swivel/dynamixel/protocol.hpp"

namespace swivel::dynamixel {
namespace {

constexpr std::array<std::uint8_t, 4> kHeader = {0xFF, 0xFF, 0xFD, 0x00};
constexpr std::size_t kHeaderBytes = 7;  // header, ID, LEN_L, LEN_H

// MSB-first CRC-16 table for polynomial 0x8005, generated at compile time.
constexpr std::array<std::uint16_t, 256> make_crc_table() {
  std::array<std::uint16_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t crc = i << 8;
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000U) != 0 ? (crc << 1) ^ 0x8005U : crc << 1;
    }
    table[i] = static_cast<std::uint16_t>(crc);
  }
  return table;
}
constexpr std::array<std::uint16_t, 256> kCrcTable = make_crc_table();

}  // namespace

std::uint16_t crc16(std::span<const std::uint8_t> data, std::uint16_t crc) noexcept {
  for (const std::uint8_t byte : data) {
    const auto index = static_cast<std::uint8_t>((crc >> 8) ^ byte);
    crc = static_cast<std::uint16_t>((crc << 8) ^ kCrcTable[index]);
  }
  return crc;
}

const char* error_number_text(std::uint8_t error) noexcept {
  switch (static_cast<ErrorNumber>(error & 0x7F)) {
    case ErrorNumber::kNone: return "no error";
    case ErrorNumber::kResultFail: return "result fail";
    case ErrorNumber::kInstructionError: return "instruction error";
    case ErrorNumber::kCrcError: return "CRC error";
    case ErrorNumber::kDataRangeError: return "data range error";
    case ErrorNumber::kDataLengthError: return "data length error";
    case ErrorNumber::kDataLimitError: return "data limit error";
    case ErrorNumber::kAccessError: return "access error";
  }
  return "unknown error number";
}

const char* hardware_error_text(std::uint8_t status) noexcept {
  // Most serious first: a shock or a failed encoder outranks a hot or overloaded motor.
  if ((status & hardware_error::kElectricalShock) != 0) return "electrical shock";
  if ((status & hardware_error::kMotorEncoder) != 0) return "motor encoder error";
  if ((status & hardware_error::kOverheating) != 0) return "overheating";
  if ((status & hardware_error::kOverload) != 0) return "overload";
  if ((status & hardware_error::kInputVoltage) != 0) return "input voltage error";
  if (status != 0) return "unknown hardware error";
  return "";
}

PacketBuilder::PacketBuilder(std::uint8_t id, Instruction instruction) noexcept
    : raw_size_(1), id_(id) {
  raw_[0] = static_cast<std::uint8_t>(instruction);
}

PacketBuilder& PacketBuilder::u8(std::uint8_t value) noexcept {
  if (raw_size_ >= raw_.size()) {
    overflow_ = true;
    return *this;
  }
  raw_[raw_size_++] = value;
  return *this;
}

PacketBuilder& PacketBuilder::u16(std::uint16_t value) noexcept {
  return u8(static_cast<std::uint8_t>(value)).u8(static_cast<std::uint8_t>(value >> 8));
}

PacketBuilder& PacketBuilder::u32(std::uint32_t value) noexcept {
  return u16(static_cast<std::uint16_t>(value)).u16(static_cast<std::uint16_t>(value >> 16));
}

PacketBuilder& PacketBuilder::bytes(std::span<const std::uint8_t> data) noexcept {
  for (const std::uint8_t b : data) u8(b);
  return *this;
}

std::span<const std::uint8_t> PacketBuilder::finish() noexcept {
  wire_size_ = 0;
  if (overflow_) return {};
  for (const std::uint8_t b : kHeader) wire_[wire_size_++] = b;
  wire_[wire_size_++] = id_;
  wire_size_ += 2;  // length, below
  const std::size_t body = wire_size_;
  for (std::size_t i = 0; i < raw_size_; ++i) {
    if (wire_size_ + 3 > wire_.size()) {  // room for a stuffing byte and the CRC
      overflow_ = true;
      return {};
    }
    wire_[wire_size_++] = raw_[i];
    if (wire_size_ - body >= 3 && wire_[wire_size_ - 3] == 0xFF && wire_[wire_size_ - 2] == 0xFF &&
        wire_[wire_size_ - 1] == 0xFD) {
      wire_[wire_size_++] = 0xFD;
    }
  }
  const std::size_t length = wire_size_ - body + 2;
  wire_[5] = static_cast<std::uint8_t>(length);
  wire_[6] = static_cast<std::uint8_t>(length >> 8);
  const std::uint16_t crc = crc16({wire_.data(), wire_size_});
  wire_[wire_size_++] = static_cast<std::uint8_t>(crc);
  wire_[wire_size_++] = static_cast<std::uint8_t>(crc >> 8);
  return {wire_.data(), wire_size_};
}

std::span<const std::uint8_t> build_ping(PacketBuilder& b) noexcept { return b.finish(); }

std::span<const std::uint8_t> build_read(PacketBuilder& b, std::uint16_t address,
                                         std::uint16_t length) noexcept {
  return b.u16(address).u16(length).finish();
}

std::span<const std::uint8_t> build_write(PacketBuilder& b, std::uint16_t address,
                                          std::span<const std::uint8_t> data) noexcept {
  return b.u16(address).bytes(data).finish();
}

std::span<const std::uint8_t> build_sync_read(PacketBuilder& b, std::uint16_t address,
                                              std::uint16_t length,
                                              std::span<const std::uint8_t> ids) noexcept {
  return b.u16(address).u16(length).bytes(ids).finish();
}

std::span<const std::uint8_t> build_sync_write(PacketBuilder& b, std::uint16_t address,
                                               std::uint16_t length,
                                               std::span<const std::uint8_t> ids,
                                               std::span<const std::uint8_t> data) noexcept {
  if (data.size() != ids.size() * length) return {};
  b.u16(address).u16(length);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    b.u8(ids[i]).bytes(data.subspan(i * length, length));
  }
  return b.finish();
}

Parser::Result Parser::feed(std::span<const std::uint8_t> data, std::size_t& consumed) noexcept {
  consumed = 0;
  while (consumed < data.size()) {
    const std::uint8_t byte = data[consumed++];
    if (size_ < kHeader.size()) {
      if (byte == kHeader[size_]) {
        buffer_[size_++] = byte;
      } else if (size_ == 2 && byte == 0xFF) {
        // FF FF FF: the last two may still start a header.
      } else {
        size_ = 0;
        if (byte == 0xFF) buffer_[size_++] = byte;
      }
      continue;
    }
    buffer_[size_++] = byte;
    if (size_ == kHeaderBytes) {
      const std::size_t length =
          static_cast<std::size_t>(buffer_[5]) | (static_cast<std::size_t>(buffer_[6]) << 8);
      if (length < 3 || kHeaderBytes + length > buffer_.size()) {
        size_ = 0;
        return Result::kBadLength;
      }
      expected_ = kHeaderBytes + length;
    }
    if (size_ > kHeaderBytes && size_ == expected_) return finish_packet();
  }
  return Result::kNeedMore;
}

Parser::Result Parser::finish_packet() noexcept {
  size_ = 0;
  last_id_ = buffer_[4];
  const std::size_t crc_at = expected_ - 2;
  const std::uint16_t crc = crc16({buffer_.data(), crc_at});
  const auto received = static_cast<std::uint16_t>(buffer_[crc_at] | (buffer_[crc_at + 1] << 8));
  if (crc != received) return Result::kCrcError;
  packet_.id = buffer_[4];
  packet_.instruction = buffer_[kHeaderBytes];
  packet_.param_count = 0;
  // Unstuff: FF FF FD FD -> FF FF FD (the instruction counts towards the pattern).
  std::size_t run = 0;  // how much of FF FF FD the last unstuffed bytes match
  run = packet_.instruction == 0xFF ? 1 : 0;
  for (std::size_t i = kHeaderBytes + 1; i < crc_at; ++i) {
    const std::uint8_t b = buffer_[i];
    if (run == 3) {
      run = 0;
      if (b == 0xFD) continue;  // the stuffing byte
    }
    packet_.params[packet_.param_count++] = b;
    if (b == 0xFF) {
      run = run >= 1 ? 2 : 1;
    } else if (b == 0xFD && run == 2) {
      run = 3;
    } else {
      run = 0;
    }
  }
  return Result::kPacket;
}

}  // namespace swivel::dynamixel
