// SPDX-License-Identifier: Apache-2.0
// Protocol 2.0 framing against the example packets of ROBOTIS's Protocol 2.0 description,
// byte stuffing both ways, the parser's resynchronisation and CRC rejection.

#include "swivel/dynamixel/protocol.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

namespace dxl = swivel::dynamixel;
using Bytes = std::vector<std::uint8_t>;

namespace {

Bytes to_vector(std::span<const std::uint8_t> s) { return {s.begin(), s.end()}; }

// Feeds `wire` whole; returns the results in order.
std::vector<dxl::Parser::Result> feed_all(dxl::Parser& parser, const Bytes& wire,
                                          std::vector<dxl::Packet>* packets = nullptr) {
  std::vector<dxl::Parser::Result> results;
  std::span<const std::uint8_t> rest(wire);
  while (!rest.empty()) {
    std::size_t used = 0;
    const auto r = parser.feed(rest, used);
    rest = rest.subspan(used);
    if (r != dxl::Parser::Result::kNeedMore) {
      results.push_back(r);
      if (r == dxl::Parser::Result::kPacket && packets != nullptr) {
        packets->push_back(parser.packet());
      }
    }
  }
  return results;
}

}  // namespace

TEST(DynamixelCrc, MatchesThePublishedPingExample) {
  // ROBOTIS's Ping example for ID 1: FF FF FD 00 01 03 00 01 | CRC 0x4E19 (19 4E).
  const Bytes body = {0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x03, 0x00, 0x01};
  EXPECT_EQ(dxl::crc16(body), 0x4E19);
  // ... and its status reply (model 1030, firmware 38): CRC 0x5D65 (65 5D).
  const Bytes status = {0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x07, 0x00, 0x55, 0x00, 0x06, 0x04, 0x26};
  EXPECT_EQ(dxl::crc16(status), 0x5D65);
}

TEST(DynamixelCrc, ChainsOverSplitInput) {
  const Bytes body = {0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x03, 0x00, 0x01};
  const std::uint16_t first = dxl::crc16(std::span(body).first(3));
  EXPECT_EQ(dxl::crc16(std::span(body).subspan(3), first), dxl::crc16(body));
  EXPECT_EQ(dxl::crc16({}), 0);
}

TEST(DynamixelBuild, PingMatchesThePublishedExample) {
  dxl::PacketBuilder b(1, dxl::Instruction::kPing);
  EXPECT_EQ(to_vector(dxl::build_ping(b)),
            (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x03, 0x00, 0x01, 0x19, 0x4E}));
}

TEST(DynamixelBuild, ReadWriteSyncLayout) {
  {
    dxl::PacketBuilder b(1, dxl::Instruction::kRead);
    const Bytes w = to_vector(dxl::build_read(b, 132, 4));
    ASSERT_EQ(w.size(), 14U);
    EXPECT_EQ(Bytes(w.begin(), w.begin() + 12),
              (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x07, 0x00, 0x02, 0x84, 0x00, 0x04, 0x00}));
    EXPECT_EQ(w[12] | (w[13] << 8), dxl::crc16(std::span(w).first(12)));
  }
  {
    dxl::PacketBuilder b(1, dxl::Instruction::kWrite);
    const std::uint8_t data[] = {0x00, 0x02, 0x00, 0x00};
    const Bytes w = to_vector(dxl::build_write(b, 116, data));
    EXPECT_EQ(Bytes(w.begin(), w.end() - 2), (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x09, 0x00, 0x03,
                                                    0x74, 0x00, 0x00, 0x02, 0x00, 0x00}));
  }
  {
    dxl::PacketBuilder b(dxl::kBroadcastId, dxl::Instruction::kSyncRead);
    const std::uint8_t ids[] = {1, 2};
    const Bytes w = to_vector(dxl::build_sync_read(b, 132, 4, ids));
    EXPECT_EQ(Bytes(w.begin(), w.end() - 2), (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0xFE, 0x09, 0x00, 0x82,
                                                    0x84, 0x00, 0x04, 0x00, 0x01, 0x02}));
  }
  {
    dxl::PacketBuilder b(dxl::kBroadcastId, dxl::Instruction::kSyncWrite);
    const std::uint8_t ids[] = {1, 2};
    const std::uint8_t data[] = {0x96, 0, 0, 0, 0xAA, 0, 0, 0};
    const Bytes w = to_vector(dxl::build_sync_write(b, 116, 4, ids, data));
    EXPECT_EQ(Bytes(w.begin(), w.end() - 2),
              (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0xFE, 0x11, 0x00, 0x83, 0x74, 0x00, 0x04,
                     0x00, 0x01, 0x96, 0x00, 0x00, 0x00, 0x02, 0xAA, 0x00, 0x00, 0x00}));
    // A data block of the wrong size is refused.
    dxl::PacketBuilder bad(dxl::kBroadcastId, dxl::Instruction::kSyncWrite);
    EXPECT_TRUE(dxl::build_sync_write(bad, 116, 4, ids, std::span(data).first(7)).empty());
  }
}

TEST(DynamixelBuild, StuffsHeaderPatternInParameters) {
  dxl::PacketBuilder b(3, dxl::Instruction::kWrite);
  const std::uint8_t data[] = {0xFF, 0xFF, 0xFD, 0x01};
  const Bytes w = to_vector(dxl::build_write(b, 0x0010, data));
  // INST 03, address 10 00, then FF FF FD FD 01: length = 1 + 2 + 5 + 2 = 10.
  EXPECT_EQ(Bytes(w.begin(), w.end() - 2), (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0x03, 0x0A, 0x00, 0x03,
                                                  0x10, 0x00, 0xFF, 0xFF, 0xFD, 0xFD, 0x01}));
  dxl::Parser parser;
  std::vector<dxl::Packet> packets;
  EXPECT_EQ(feed_all(parser, w, &packets),
            std::vector<dxl::Parser::Result>{dxl::Parser::Result::kPacket});
  ASSERT_EQ(packets.size(), 1U);
  EXPECT_EQ(packets[0].id, 3);
  EXPECT_EQ(packets[0].instruction, 0x03);
  ASSERT_EQ(packets[0].param_count, 6U);
  EXPECT_EQ(Bytes(packets[0].params.begin(), packets[0].params.begin() + 6),
            (Bytes{0x10, 0x00, 0xFF, 0xFF, 0xFD, 0x01}));
}

TEST(DynamixelParser, DecodesThePublishedStatusAfterGarbageAndSplitInput) {
  const Bytes status = {0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x07, 0x00,
                        0x55, 0x00, 0x06, 0x04, 0x26, 0x65, 0x5D};
  Bytes wire = {0x00, 0xFF, 0x12, 0xFF, 0xFF, 0xFF};  // noise, incl. a false header start
  wire.insert(wire.end(), status.begin(), status.end());
  dxl::Parser parser;
  // Byte by byte: only the last byte completes the packet.
  for (std::size_t i = 0; i < wire.size(); ++i) {
    std::size_t used = 0;
    const auto r = parser.feed(std::span(wire).subspan(i, 1), used);
    EXPECT_EQ(used, 1U);
    EXPECT_EQ(r,
              i + 1 == wire.size() ? dxl::Parser::Result::kPacket : dxl::Parser::Result::kNeedMore)
        << "at byte " << i;
  }
  const dxl::Packet& p = parser.packet();
  EXPECT_TRUE(p.is_status());
  EXPECT_EQ(p.id, 1);
  EXPECT_EQ(p.error(), 0);
  ASSERT_EQ(p.data().size(), 3U);
  EXPECT_EQ(dxl::get_u16(p.data(), 0), 1030);  // model number
  EXPECT_EQ(p.data()[2], 38);                  // firmware
}

TEST(DynamixelParser, RejectsACorruptCrcAndRecoversOnTheNextPacket) {
  Bytes bad = {0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x07, 0x00, 0x55, 0x00, 0x06, 0x04, 0x26, 0x65, 0x5C};
  Bytes good = {0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x07, 0x00, 0x55, 0x00, 0x06, 0x04, 0x26, 0x65, 0x5D};
  Bytes wire = bad;
  wire.insert(wire.end(), good.begin(), good.end());
  dxl::Parser parser;
  EXPECT_EQ(feed_all(parser, wire),
            (std::vector<dxl::Parser::Result>{dxl::Parser::Result::kCrcError,
                                              dxl::Parser::Result::kPacket}));
}

TEST(DynamixelParser, RejectsImpossibleLengths) {
  const Bytes wire = {0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x02, 0x00};
  dxl::Parser parser;
  EXPECT_EQ(feed_all(parser, wire),
            std::vector<dxl::Parser::Result>{dxl::Parser::Result::kBadLength});
  const Bytes huge = {0xFF, 0xFF, 0xFD, 0x00, 0x01, 0xFF, 0xFF};
  EXPECT_EQ(feed_all(parser, huge),
            std::vector<dxl::Parser::Result>{dxl::Parser::Result::kBadLength});
}

TEST(DynamixelParser, RoundTripsEveryStuffingPosition) {
  // The header pattern at each offset of the parameters, and overlapping runs.
  for (std::size_t at = 0; at < 6; ++at) {
    Bytes data(8, 0x11);
    data[at] = 0xFF;
    data[at + 1] = 0xFF;
    data[at + 2] = 0xFD;
    dxl::PacketBuilder b(7, dxl::Instruction::kWrite);
    const Bytes w = to_vector(dxl::build_write(b, 0xFDFF, data));
    dxl::Parser parser;
    std::vector<dxl::Packet> packets;
    ASSERT_EQ(feed_all(parser, w, &packets),
              std::vector<dxl::Parser::Result>{dxl::Parser::Result::kPacket});
    const dxl::Packet& p = packets[0];
    ASSERT_EQ(p.param_count, 10U) << at;
    EXPECT_EQ(dxl::get_u16({p.params.data(), p.param_count}, 0), 0xFDFF);
    EXPECT_EQ(Bytes(p.params.begin() + 2, p.params.begin() + 10), data) << at;
  }
  const Bytes tricky = {0xFF, 0xFF, 0xFF, 0xFD, 0xFD, 0xFF, 0xFF, 0xFD};
  dxl::PacketBuilder b(7, dxl::Instruction::kWrite);
  const Bytes w = to_vector(dxl::build_write(b, 1, tricky));
  dxl::Parser parser;
  std::vector<dxl::Packet> packets;
  ASSERT_EQ(feed_all(parser, w, &packets).size(), 1U);
  ASSERT_EQ(packets.size(), 1U);
  EXPECT_EQ(Bytes(packets[0].params.begin() + 2,
                  packets[0].params.begin() + static_cast<long>(packets[0].param_count)),
            tricky);
}

TEST(DynamixelErrors, NamesHardwareErrorBitsAndErrorNumbers) {
  EXPECT_STREQ(dxl::hardware_error_text(0), "");
  EXPECT_STREQ(dxl::hardware_error_text(dxl::hardware_error::kInputVoltage), "input voltage error");
  EXPECT_STREQ(dxl::hardware_error_text(dxl::hardware_error::kOverheating), "overheating");
  EXPECT_STREQ(dxl::hardware_error_text(dxl::hardware_error::kMotorEncoder), "motor encoder error");
  EXPECT_STREQ(dxl::hardware_error_text(dxl::hardware_error::kElectricalShock), "electrical shock");
  EXPECT_STREQ(dxl::hardware_error_text(dxl::hardware_error::kOverload), "overload");
  EXPECT_STREQ(dxl::hardware_error_text(0x02), "unknown hardware error");
  EXPECT_STREQ(dxl::hardware_error_text(dxl::hardware_error::kOverload |
                                        dxl::hardware_error::kElectricalShock),
               "electrical shock");
  EXPECT_STREQ(dxl::error_number_text(0x80 | 3), "CRC error");
  EXPECT_STREQ(dxl::error_number_text(7), "access error");
}

TEST(DynamixelBuild, MatchesThePublishedReadWriteAndSyncExamples) {
  // The e-manual's examples, CRC bytes included.
  dxl::PacketBuilder read(1, dxl::Instruction::kRead);
  EXPECT_EQ(
      to_vector(dxl::build_read(read, 132, 4)),
      (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x07, 0x00, 0x02, 0x84, 0x00, 0x04, 0x00, 0x1D, 0x15}));
  dxl::PacketBuilder write(1, dxl::Instruction::kWrite);
  const std::uint8_t goal[] = {0x00, 0x02, 0x00, 0x00};
  EXPECT_EQ(to_vector(dxl::build_write(write, 116, goal)),
            (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x09, 0x00, 0x03, 0x74, 0x00, 0x00, 0x02, 0x00,
                   0x00, 0xCA, 0x89}));
  const std::uint8_t ids[] = {1, 2};
  dxl::PacketBuilder sync_read(dxl::kBroadcastId, dxl::Instruction::kSyncRead);
  EXPECT_EQ(to_vector(dxl::build_sync_read(sync_read, 132, 4, ids)),
            (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0xFE, 0x09, 0x00, 0x82, 0x84, 0x00, 0x04, 0x00, 0x01,
                   0x02, 0xCE, 0xFA}));
  dxl::PacketBuilder sync_write(dxl::kBroadcastId, dxl::Instruction::kSyncWrite);
  const std::uint8_t goals[] = {0x96, 0, 0, 0, 0xAA, 0, 0, 0};
  EXPECT_EQ(to_vector(dxl::build_sync_write(sync_write, 116, 4, ids, goals)),
            (Bytes{0xFF, 0xFF, 0xFD, 0x00, 0xFE, 0x11, 0x00, 0x83, 0x74, 0x00, 0x04, 0x00,
                   0x01, 0x96, 0x00, 0x00, 0x00, 0x02, 0xAA, 0x00, 0x00, 0x00, 0x82, 0x87}));
}
