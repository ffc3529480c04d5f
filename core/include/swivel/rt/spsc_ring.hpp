// SPDX-License-Identifier: Apache-2.0
#pragma once
// Bounded lock-free ring for exactly one producer thread and one consumer thread. Storage is
// inline (no allocation); elements are copied in and out, so they must be trivially copyable.

#include <array>
#include <atomic>
#include <cstddef>
#include <type_traits>

namespace swivel::rt {

/// Cache line size used to keep indices written by different threads apart. A constant rather
/// than std::hardware_destructive_interference_size, whose value may differ between compilers.
inline constexpr std::size_t kCacheLineBytes = 64;

/// Single-producer single-consumer ring of `CapacityItems` elements (a power of two).
/// try_push() may only be called from one thread and try_pop() from one (other) thread.
/// Every method is real-time safe: no allocation, no lock, no system call.
template <class T, std::size_t CapacityItems>
class SpscRing {
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing elements must be trivially copyable");
  static_assert(std::atomic<std::size_t>::is_always_lock_free,
                "SpscRing needs lock-free std::size_t atomics");
  static_assert(CapacityItems >= 2 && (CapacityItems & (CapacityItems - 1)) == 0,
                "SpscRing capacity must be a power of two");

 public:
  SpscRing() noexcept = default;
  ~SpscRing() = default;
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  [[nodiscard]] static constexpr std::size_t capacity() noexcept { return CapacityItems; }

  /// Producer only. Real-time safe. Copies `item` in; false (item dropped) when full.
  bool try_push(const T& item) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_cache_ == CapacityItems) {
      // Looks full with the stale view: refresh it once.
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail - head_cache_ == CapacityItems) return false;
    }
    slots_[tail & kMask] = item;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Consumer only. Real-time safe. Copies the oldest element out; false when empty.
  bool try_pop(T& out) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_cache_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head == tail_cache_) return false;
    }
    out = slots_[head & kMask];
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Any thread. Real-time safe. A snapshot that may be stale by the time it is used.
  [[nodiscard]] std::size_t size_approx() const noexcept {
    const std::size_t head = head_.load(std::memory_order_acquire);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    return tail >= head ? tail - head : 0;
  }

 private:
  static constexpr std::size_t kMask = CapacityItems - 1;

  // Consumer-owned line: its index and its cached copy of the producer's index.
  alignas(kCacheLineBytes) std::atomic<std::size_t> head_{0};
  std::size_t tail_cache_ = 0;
  // Producer-owned line.
  alignas(kCacheLineBytes) std::atomic<std::size_t> tail_{0};
  std::size_t head_cache_ = 0;
  alignas(kCacheLineBytes) std::array<T, CapacityItems> slots_{};
};

/// Consumer only. Pops at most `limit` items, handing each to `take`; returns how many. A
/// consumer that drains with a plain `while (try_pop(...))` can be held indefinitely by a
/// producer pushing as fast as it pops; a real-time consumer bounds its work instead and
/// leaves the rest for its next cycle. `Ring` is any type with SpscRing's try_pop().
template <class Ring, class Item, class Take>
std::size_t pop_at_most(Ring& ring, Item& item, std::size_t limit, Take&& take) noexcept {
  std::size_t popped = 0;
  while (popped < limit && ring.try_pop(item)) {
    ++popped;
    take(item);
  }
  return popped;
}

}  // namespace swivel::rt
