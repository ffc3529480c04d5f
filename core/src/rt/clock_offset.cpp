// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/clock_offset.hpp"

#include <time.h>

#include <cmath>
#include <limits>

#include "swivel/clock.hpp"

namespace swivel::rt {
namespace {

std::int64_t read_ns(clockid_t clock) noexcept {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

}  // namespace

ClockOffsetMeasurement measure_clock_offset(int tries) noexcept {
  ClockOffsetMeasurement best;
  std::int64_t best_width = std::numeric_limits<std::int64_t>::max();
  for (int i = 0; i < (tries < 1 ? 1 : tries); ++i) {
    const std::int64_t before = read_ns(CLOCK_MONOTONIC);
    const std::int64_t real = read_ns(CLOCK_REALTIME);
    const std::int64_t after = read_ns(CLOCK_MONOTONIC);
    const std::int64_t width = after - before;
    if (width < best_width) {
      best_width = width;
      best.offset_ns = real - (before + width / 2);
      best.uncertainty_ns = (width + 1) / 2;
    }
  }
  return best;
}

void ClockOffset::refresh() noexcept {
  const ClockOffsetMeasurement m = measure_clock_offset();
  uncertainty_ns_.store(m.uncertainty_ns, std::memory_order_release);
  offset_ns_.store(m.offset_ns, std::memory_order_release);
}

std::int64_t ClockOffset::to_realtime_ns(double monotonic_s) const noexcept {
  return std::llround(monotonic_s * 1e9) + offset_ns();
}

}  // namespace swivel::rt
