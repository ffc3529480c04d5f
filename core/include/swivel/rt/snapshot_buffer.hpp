// SPDX-License-Identifier: Apache-2.0
#pragma once
// Latest-value buffer: one writer publishes, any number of readers copy the newest value.
// A sequence lock whose payload is stored as 64-bit atomic words (release stores, acquire
// loads), so that a reader overlapping a write is not a data race (ThreadSanitizer accepts
// it) and a torn copy is detected by the sequence check and retried. The writer never waits.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "swivel/rt/spsc_ring.hpp"

namespace swivel::rt {

/// Single-writer multi-reader latest value of a trivially copyable T.
template <class T>
class SnapshotBuffer {
  static_assert(std::is_trivially_copyable_v<T>,
                "SnapshotBuffer values must be trivially copyable");
  static_assert(std::atomic<std::uint64_t>::is_always_lock_free,
                "SnapshotBuffer needs lock-free 64-bit atomics");

 public:
  /// Starts out holding `initial`. Does not allocate.
  explicit SnapshotBuffer(const T& initial = T{}) noexcept {
    store_words(initial, std::memory_order_relaxed);
  }
  ~SnapshotBuffer() = default;
  SnapshotBuffer(const SnapshotBuffer&) = delete;
  SnapshotBuffer& operator=(const SnapshotBuffer&) = delete;

  /// Writer only (one thread). Real-time safe, wait-free.
  void write(const T& value) noexcept {
    const std::uint64_t sequence = sequence_.load(std::memory_order_relaxed);
    sequence_.store(sequence + 1, std::memory_order_relaxed);  // odd: write in progress
    // Release stores of the words: a reader that sees any new word also sees the odd count.
    store_words(value, std::memory_order_release);
    sequence_.store(sequence + 2, std::memory_order_release);
  }

  /// Any thread. One attempt: true and `out` set when no write overlapped the copy.
  /// Real-time safe and wait-free.
  bool try_read(T& out) const noexcept {
    const std::uint64_t before = sequence_.load(std::memory_order_acquire);
    if ((before & 1U) != 0) return false;
    Words words;
    for (std::size_t i = 0; i < kWordCount; ++i) {
      // Acquire loads keep the second sequence read after them (no standalone fences:
      // ThreadSanitizer does not model those). Plain loads on x86.
      words[i] = words_[i].load(std::memory_order_acquire);
    }
    if (sequence_.load(std::memory_order_relaxed) != before) return false;
    // Trivially copyable (asserted above), so copying its bytes is copying it.
    std::memcpy(static_cast<void*>(&out), words.data(), sizeof(T));
    return true;
  }

  /// Any thread. Copies the newest value, retrying while the writer is mid-write. Lock-free
  /// (not wait-free): a reader can only be delayed by writes, which take well under a
  /// microsecond each.
  [[nodiscard]] T read() const noexcept {
    T out;  // NOLINT(cppcoreguidelines-pro-type-member-init): try_read() writes all of it
    while (!try_read(out)) {
    }
    return out;
  }

  /// Any thread. Number of completed writes; tells a reader whether anything new arrived.
  [[nodiscard]] std::uint64_t version() const noexcept {
    return sequence_.load(std::memory_order_acquire) / 2;
  }

 private:
  static constexpr std::size_t kWordCount = (sizeof(T) + 7) / 8;
  using Words = std::array<std::uint64_t, kWordCount>;

  void store_words(const T& value, std::memory_order order) noexcept {
    Words words{};
    std::memcpy(words.data(), static_cast<const void*>(&value), sizeof(T));
    for (std::size_t i = 0; i < kWordCount; ++i) {
      words_[i].store(words[i], order);
    }
  }

  alignas(kCacheLineBytes) std::atomic<std::uint64_t> sequence_{0};
  alignas(kCacheLineBytes) std::array<std::atomic<std::uint64_t>, kWordCount> words_{};
};

}  // namespace swivel::rt
