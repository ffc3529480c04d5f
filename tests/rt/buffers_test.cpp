// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <cstdint>

#include "swivel/rt/snapshot_buffer.hpp"
#include "swivel/rt/spsc_ring.hpp"
#include "swivel/rt/state_snapshot.hpp"

namespace swivel::rt {
namespace {

TEST(SpscRing, PopsInPushOrder) {
  SpscRing<int, 8> ring;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(ring.try_push(i));
  for (int i = 0; i < 5; ++i) {
    int out = -1;
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out, i);
  }
}

TEST(SpscRing, PopOnEmptyFailsAndLeavesOutput) {
  SpscRing<int, 4> ring;
  int out = 42;
  EXPECT_FALSE(ring.try_pop(out));
  EXPECT_EQ(out, 42);
}

TEST(SpscRing, RefusesPushWhenFullAndAcceptsAfterPop) {
  SpscRing<int, 4> ring;
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(ring.try_push(i));
  EXPECT_FALSE(ring.try_push(99));
  EXPECT_EQ(ring.size_approx(), 4U);
  int out = -1;
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out, 0);
  EXPECT_TRUE(ring.try_push(4));
  for (int expected = 1; expected <= 4; ++expected) {
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out, expected);
  }
  EXPECT_EQ(ring.size_approx(), 0U);
}

TEST(SpscRing, WrapsAroundManyTimes) {
  SpscRing<std::uint64_t, 4> ring;
  std::uint64_t next_pop = 0;
  for (std::uint64_t i = 0; i < 1000; ++i) {
    ASSERT_TRUE(ring.try_push(i));
    if (i % 3 != 0) {
      std::uint64_t out = 0;
      ASSERT_TRUE(ring.try_pop(out));
      EXPECT_EQ(out, next_pop++);
    }
    if (ring.size_approx() == decltype(ring)::capacity()) {
      std::uint64_t out = 0;
      while (ring.try_pop(out)) EXPECT_EQ(out, next_pop++);
    }
  }
}

TEST(SpscRing, CarriesVelocityCommands) {
  SpscRing<VelocityCommand, 2> ring;
  VelocityCommand in;
  in.twist = {0.3, -0.1, 0.6};
  in.received_s = 12.5;
  in.sequence = 7;
  ASSERT_TRUE(ring.try_push(in));
  VelocityCommand out;
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out.twist.vx_mps, 0.3);
  EXPECT_EQ(out.twist.vy_mps, -0.1);
  EXPECT_EQ(out.twist.wz_radps, 0.6);
  EXPECT_EQ(out.received_s, 12.5);
  EXPECT_EQ(out.sequence, 7U);
}

// A producer that never runs dry (it refills faster than the consumer pops): the bound is
// all that ends the drain.
struct EndlessRing {
  int next = 0;
  bool try_pop(int& out) noexcept {
    out = next++;
    return true;
  }
};

TEST(PopAtMost, StopsAtTheLimitWhateverTheProducerDoes) {
  EndlessRing ring;
  int item = 0;
  int last = -1;
  const std::size_t popped = pop_at_most(ring, item, 64, [&](int v) { last = v; });
  EXPECT_EQ(popped, 64U);
  EXPECT_EQ(last, 63);
}

TEST(PopAtMost, TakesWhatThereIsBelowTheLimit) {
  SpscRing<int, 8> ring;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(ring.try_push(i));
  int item = 0;
  int sum = 0;
  EXPECT_EQ(pop_at_most(ring, item, 8, [&](int v) { sum += v; }), 5U);
  EXPECT_EQ(sum, 0 + 1 + 2 + 3 + 4);
  EXPECT_EQ(pop_at_most(ring, item, 8, [&](int v) { sum += v; }), 0U);
}

TEST(SnapshotBuffer, ReadsInitialValueBeforeAnyWrite) {
  SnapshotBuffer<Pose2> buffer(Pose2{1.0, 2.0, 3.0});
  const Pose2 p = buffer.read();
  EXPECT_EQ(p.x_m, 1.0);
  EXPECT_EQ(p.y_m, 2.0);
  EXPECT_EQ(p.yaw_rad, 3.0);
  EXPECT_EQ(buffer.version(), 0U);
}

TEST(SnapshotBuffer, ReadReturnsNewestWrite) {
  SnapshotBuffer<StateSnapshot> buffer;
  StateSnapshot s;
  for (std::uint64_t i = 1; i <= 3; ++i) {
    s.cycle = i;
    s.estimate.pose.x_m = 0.5 * static_cast<double>(i);
    s.localization_plugin = {'r', 'a', 'w', '_', 'e', 'g', '\0'};
    buffer.write(s);
  }
  const StateSnapshot out = buffer.read();
  EXPECT_EQ(out.cycle, 3U);
  EXPECT_EQ(out.estimate.pose.x_m, 1.5);
  EXPECT_STREQ(out.localization_plugin.data(), "raw_eg");
  EXPECT_EQ(buffer.version(), 3U);
}

TEST(SnapshotBuffer, HandlesSizesThatAreNotWordMultiples) {
  struct Odd {
    char bytes[13];
  };
  SnapshotBuffer<Odd> buffer;
  Odd in{};
  for (int i = 0; i < 13; ++i) in.bytes[i] = static_cast<char>('a' + i);
  buffer.write(in);
  Odd out{};
  ASSERT_TRUE(buffer.try_read(out));
  for (int i = 0; i < 13; ++i) EXPECT_EQ(out.bytes[i], static_cast<char>('a' + i));
}

}  // namespace
}  // namespace swivel::rt
