// SPDX-License-Identifier: Apache-2.0
#pragma once
// Latest value for exactly one producer thread and one consumer thread: a triple buffer.
// The producer always writes into a slot of its own and publishes it by exchanging its index
// with the shared "middle" one; the consumer takes the middle slot by exchanging it with the
// slot it read last. Both sides are wait-free (one atomic exchange each), neither ever sees a
// torn value, and the consumer always gets the newest complete value: a value the consumer
// had not taken yet is replaced, never queued, so the newest always wins.

#include <array>
#include <atomic>
#include <cstdint>
#include <type_traits>

#include "swivel/rt/spsc_ring.hpp"

namespace swivel::rt {

/// Single-producer single-consumer latest value of a trivially copyable T. publish() may only
/// be called from one thread and take() from one (other) thread. Every method is real-time
/// safe: no allocation, no lock, no system call, no retry loop.
template <class T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue values must be trivially copyable");
  static_assert(std::atomic<std::uint8_t>::is_always_lock_free,
                "LatestValue needs lock-free 8-bit atomics");

 public:
  LatestValue() noexcept = default;
  ~LatestValue() = default;
  LatestValue(const LatestValue&) = delete;
  LatestValue& operator=(const LatestValue&) = delete;

  /// Producer only. Real-time safe, wait-free. Publishes `value`; returns true when it
  /// replaced a value the consumer had not taken (that one is gone).
  bool publish(const T& value) noexcept {
    slots_[back_].value = value;
    const std::uint8_t previous =
        middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    back_ = static_cast<std::uint8_t>(previous & kIndexMask);
    return (previous & kFresh) != 0;
  }

  /// Consumer only. Real-time safe, wait-free. True and `out` set to the newest value
  /// published since the last take(); false (and `out` untouched) when nothing new arrived.
  bool take(T& out) noexcept {
    if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) return false;
    const std::uint8_t previous = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = static_cast<std::uint8_t>(previous & kIndexMask);
    out = slots_[front_].value;
    return true;
  }

 private:
  static constexpr std::uint8_t kIndexMask = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;  // the middle slot holds an untaken value

  struct alignas(kCacheLineBytes) Slot {
    T value{};
  };

  std::array<Slot, 3> slots_{};
  alignas(kCacheLineBytes) std::atomic<std::uint8_t> middle_{1};
  alignas(kCacheLineBytes) std::uint8_t back_ = 0;   // producer-owned
  alignas(kCacheLineBytes) std::uint8_t front_ = 2;  // consumer-owned
};

}  // namespace swivel::rt
