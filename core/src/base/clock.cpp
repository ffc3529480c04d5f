// SPDX-License-Identifier: Apache-2.0
#include "swivel/clock.hpp"

#include <time.h>

namespace swivel {

std::int64_t monotonic_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

double monotonic_s() noexcept { return static_cast<double>(monotonic_ns()) * 1e-9; }

}  // namespace swivel
