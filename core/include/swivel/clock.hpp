// SPDX-License-Identifier: Apache-2.0
#pragma once
// The one clock of Swivel: CLOCK_MONOTONIC, the clock of the real-time loop, of every
// `stamp_s` and `received_s` in the state and on DDS, and of systemd's MONOTONIC_USEC.

#include <cstdint>

namespace swivel {

/// Nanoseconds in a second, for timespec arithmetic.
inline constexpr std::int64_t kNsPerS = 1'000'000'000;

/// CLOCK_MONOTONIC now, nanoseconds. Real-time safe (vDSO, no system call on Linux).
std::int64_t monotonic_ns() noexcept;

/// CLOCK_MONOTONIC now, seconds. Real-time safe.
double monotonic_s() noexcept;

}  // namespace swivel
