// SPDX-License-Identifier: Apache-2.0
// Two threads hammering the lock-free buffers. Under ThreadSanitizer (tsan preset) these
// also prove the absence of data races; in every build they check that nothing is lost,
// duplicated, reordered or torn.

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "swivel/rt/latest_value.hpp"
#include "swivel/rt/snapshot_buffer.hpp"
#include "swivel/rt/spsc_ring.hpp"

namespace swivel::rt {
namespace {

#if defined(__SANITIZE_THREAD__)
constexpr std::uint64_t kItems = 200'000;
#else
constexpr std::uint64_t kItems = 2'000'000;
#endif

struct Item {
  std::uint64_t sequence;
  std::uint64_t check;  // ~sequence: a torn copy would break the pair
  std::array<double, 3> payload;
};

TEST(SpscRingStress, DeliversEverythingInOrderAcrossThreads) {
  static SpscRing<Item, 128> ring;  // static: large, and kept off the test thread's stack
  std::thread producer([] {
    for (std::uint64_t i = 0; i < kItems;) {
      const Item item{i, ~i, {static_cast<double>(i), 0.5, -1.0}};
      if (ring.try_push(item)) {
        ++i;
      } else {
        std::this_thread::yield();
      }
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t mismatches = 0;
  while (expected < kItems) {
    Item item{};
    if (!ring.try_pop(item)) {
      std::this_thread::yield();
      continue;
    }
    if (item.sequence != expected || item.check != ~expected ||
        item.payload[0] != static_cast<double>(expected)) {
      ++mismatches;
    }
    ++expected;
  }
  producer.join();
  EXPECT_EQ(mismatches, 0U);
  Item extra{};
  EXPECT_FALSE(ring.try_pop(extra));
}

struct Wide {
  std::array<std::uint64_t, 24> words;  // every word equal to the write's sequence
};

TEST(SnapshotBufferStress, ReadersNeverSeeTornOrOlderValues) {
  static SnapshotBuffer<Wide> buffer;
  std::atomic<bool> done{false};
  constexpr int kReaders = 2;
  std::array<std::uint64_t, kReaders> torn{};
  std::array<std::uint64_t, kReaders> backwards{};
  std::vector<std::thread> readers;
  readers.reserve(kReaders);
  for (int r = 0; r < kReaders; ++r) {
    readers.emplace_back([&, r] {
      std::uint64_t last = 0;
      do {
        const Wide w = buffer.read();
        for (std::uint64_t word : w.words) {
          if (word != w.words[0]) {
            ++torn[r];
            break;
          }
        }
        if (w.words[0] < last) ++backwards[r];
        last = w.words[0];
      } while (!done.load(std::memory_order_acquire));
    });
  }
  Wide w{};
  for (std::uint64_t i = 1; i <= kItems / 4; ++i) {
    w.words.fill(i);
    buffer.write(w);
  }
  done.store(true, std::memory_order_release);
  for (auto& t : readers) t.join();
  for (int r = 0; r < kReaders; ++r) {
    EXPECT_EQ(torn[r], 0U) << "reader " << r;
    EXPECT_EQ(backwards[r], 0U) << "reader " << r;
  }
  EXPECT_EQ(buffer.read().words[0], kItems / 4);
}

TEST(LatestValueStress, ConsumerGetsOnlyWholeNewerValuesAndFinallyTheNewest) {
  static LatestValue<Item> latest;
  std::atomic<bool> done{false};
  std::uint64_t taken = 0;
  std::uint64_t torn = 0;
  std::uint64_t not_newer = 0;
  std::uint64_t last = 0;
  std::thread consumer([&] {
    Item item{};
    // Once `done` is seen, one more take() collects whatever was published last.
    for (bool finishing = false;;) {
      finishing = done.load(std::memory_order_acquire);
      if (latest.take(item)) {
        ++taken;
        if (item.check != ~item.sequence || item.payload[2] != static_cast<double>(item.sequence)) {
          ++torn;
        }
        if (item.sequence <= last) ++not_newer;
        last = item.sequence;
      }
      if (finishing) break;
    }
  });
  std::uint64_t replaced = 0;
  for (std::uint64_t i = 1; i <= kItems; ++i) {
    const auto value = static_cast<double>(i);
    if (latest.publish(Item{i, ~i, {value, value, value}})) ++replaced;
  }
  done.store(true, std::memory_order_release);
  consumer.join();
  EXPECT_EQ(torn, 0U);
  EXPECT_EQ(not_newer, 0U);
  EXPECT_EQ(last, kItems) << "the newest value must win";
  EXPECT_GT(taken, 0U);
  // Every value was either taken or replaced by a newer one before it was.
  EXPECT_EQ(taken + replaced, kItems);
}

}  // namespace
}  // namespace swivel::rt
