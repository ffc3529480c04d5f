// SPDX-License-Identifier: Apache-2.0
#include "swivel/dynamixel/bus.hpp"

#include <algorithm>
#include <cstring>

#include "swivel/clock.hpp"

namespace swivel::dynamixel {

const char* bus_result_text(BusResult result) noexcept {
  switch (result) {
    case BusResult::kOk: return "ok";
    case BusResult::kTimeout: return "no status packet";
    case BusResult::kCrcError: return "CRC error";
    case BusResult::kIoError: return "port error";
    case BusResult::kBadReply: return "malformed status packet";
  }
  return "?";
}

BusResult Bus::send(std::span<const std::uint8_t> wire) noexcept {
  if (wire.empty()) return BusResult::kIoError;
  // Whatever is still buffered answers an earlier request: drop it.
  rx_begin_ = rx_end_ = 0;
  parser_.reset();
  port_.discard_input();
  return port_.write_all(wire) ? BusResult::kOk : BusResult::kIoError;
}

BusResult Bus::receive(std::uint8_t id, double deadline_s) noexcept {
  for (;;) {
    while (rx_begin_ < rx_end_) {
      std::size_t used = 0;
      const Parser::Result r = parser_.feed({rx_.data() + rx_begin_, rx_end_ - rx_begin_}, used);
      rx_begin_ += used;
      if (r == Parser::Result::kCrcError) {
        ++crc_errors_;
        if (parser_.last_id() == id) return BusResult::kCrcError;
      } else if (r == Parser::Result::kPacket) {
        const Packet& p = parser_.packet();
        if (p.is_status() && p.id == id) return BusResult::kOk;
      }
    }
    const double left_s = deadline_s - monotonic_s();
    if (left_s <= 0.0) return BusResult::kTimeout;
    const ssize_t n = port_.read_some(rx_, left_s);
    if (n < 0) return BusResult::kIoError;
    rx_begin_ = 0;
    rx_end_ = static_cast<std::size_t>(n);
  }
}

BusResult Bus::ping(std::uint8_t id, double timeout_s, std::uint8_t& error,
                    std::uint16_t* model) noexcept {
  PacketBuilder b(id, Instruction::kPing);
  const double deadline = monotonic_s() + timeout_s;
  if (BusResult r = send(build_ping(b)); r != BusResult::kOk) return r;
  const BusResult r = receive(id, deadline);
  if (r != BusResult::kOk) return r;
  const Packet& p = parser_.packet();
  error = p.error();
  // Protocol 2.0 PING status: model number (2 bytes) and firmware version.
  if (model != nullptr) {
    if (p.data().size() < 3) return BusResult::kBadReply;
    *model = get_u16(p.data(), 0);
  }
  return r;
}

BusResult Bus::read(std::uint8_t id, std::uint16_t address, std::span<std::uint8_t> out,
                    double timeout_s, std::uint8_t& error) noexcept {
  PacketBuilder b(id, Instruction::kRead);
  const double deadline = monotonic_s() + timeout_s;
  if (BusResult r = send(build_read(b, address, static_cast<std::uint16_t>(out.size())));
      r != BusResult::kOk) {
    return r;
  }
  const BusResult r = receive(id, deadline);
  if (r != BusResult::kOk) return r;
  const Packet& p = parser_.packet();
  error = p.error();
  if ((error & 0x7F) != 0) return BusResult::kOk;  // no data with an error number
  if (p.data().size() != out.size()) return BusResult::kBadReply;
  std::memcpy(out.data(), p.data().data(), out.size());
  return BusResult::kOk;
}

BusResult Bus::write(std::uint8_t id, std::uint16_t address, std::span<const std::uint8_t> data,
                     double timeout_s, std::uint8_t& error) noexcept {
  PacketBuilder b(id, Instruction::kWrite);
  const double deadline = monotonic_s() + timeout_s;
  if (BusResult r = send(build_write(b, address, data)); r != BusResult::kOk) return r;
  const BusResult r = receive(id, deadline);
  if (r == BusResult::kOk) error = parser_.packet().error();
  return r;
}

bool Bus::sync_write(std::uint16_t address, std::uint16_t length, std::span<const std::uint8_t> ids,
                     std::span<const std::uint8_t> data) noexcept {
  PacketBuilder b(kBroadcastId, Instruction::kSyncWrite);
  return send(build_sync_write(b, address, length, ids, data)) == BusResult::kOk;
}

bool Bus::sync_read(std::uint16_t address, std::uint16_t length, std::span<const std::uint8_t> ids,
                    std::span<SyncReply> out, double timeout_s) noexcept {
  for (std::size_t i = 0; i < ids.size(); ++i) out[i] = SyncReply{};
  if (length > SyncReply::kMaxData || out.size() < ids.size()) return false;
  PacketBuilder b(kBroadcastId, Instruction::kSyncRead);
  const double deadline = monotonic_s() + timeout_s;
  if (send(build_sync_read(b, address, length, ids)) != BusResult::kOk) return false;
  std::size_t pending = ids.size();
  while (pending > 0) {
    while (rx_begin_ < rx_end_ && pending > 0) {
      std::size_t used = 0;
      const Parser::Result r = parser_.feed({rx_.data() + rx_begin_, rx_end_ - rx_begin_}, used);
      rx_begin_ += used;
      if (r != Parser::Result::kPacket && r != Parser::Result::kCrcError) continue;
      if (r == Parser::Result::kCrcError) ++crc_errors_;
      const std::uint8_t id =
          r == Parser::Result::kPacket ? parser_.packet().id : parser_.last_id();
      const auto it = std::find(ids.begin(), ids.end(), id);
      if (it == ids.end()) continue;
      SyncReply& reply = out[static_cast<std::size_t>(it - ids.begin())];
      if (reply.result != BusResult::kTimeout) continue;  // already answered
      --pending;
      if (r == Parser::Result::kCrcError) {
        reply.result = BusResult::kCrcError;
        continue;
      }
      const Packet& p = parser_.packet();
      reply.error = p.error();
      if (!p.is_status() || p.data().size() != length) {
        reply.result = (reply.error & 0x7F) != 0 ? BusResult::kOk : BusResult::kBadReply;
        continue;
      }
      std::memcpy(reply.data.data(), p.data().data(), length);
      reply.result = BusResult::kOk;
    }
    if (pending == 0) break;
    const double left_s = deadline - monotonic_s();
    if (left_s <= 0.0) break;
    const ssize_t n = port_.read_some(rx_, left_s);
    if (n < 0) return false;
    rx_begin_ = 0;
    rx_end_ = static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace swivel::dynamixel
