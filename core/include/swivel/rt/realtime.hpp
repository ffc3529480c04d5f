// SPDX-License-Identifier: Apache-2.0
#pragma once
// Operating-system set-up for a real-time thread: SCHED_FIFO, locked memory, CPU wake-up
// latency, and absolute-time sleeping on CLOCK_MONOTONIC. Where the system refuses, the
// set-up functions return a one-line warning instead of failing: the loop then runs as an
// ordinary SCHED_OTHER thread.

#include <time.h>

#include <cstdint>
#include <string>
#include <vector>

#include "swivel/clock.hpp"

namespace swivel::rt {

/// Real-time safe. Nanoseconds since the clock's epoch as a timespec.
timespec to_timespec(std::int64_t ns) noexcept;

/// Real-time safe (a blocking sleep, which is what a periodic loop wants). Sleeps until
/// CLOCK_MONOTONIC reaches `deadline_ns` with clock_nanosleep(TIMER_ABSTIME), resuming after
/// signals, so that the wake-up time does not drift with the time the caller spent working.
void sleep_until_ns(std::int64_t deadline_ns) noexcept;

/// Not real-time safe (set-up). Makes the calling thread SCHED_FIFO at `priority` (1..99).
/// @returns an empty string on success, else a one-line warning naming the reason.
std::string make_thread_fifo(int priority);

/// Not real-time safe (set-up). mlockall(MCL_CURRENT | MCL_FUTURE) for the whole process.
/// @returns an empty string on success, else a one-line warning.
std::string lock_process_memory();

/// Not real-time safe (set-up). Touches `bytes` of the calling thread's stack so that its
/// pages are resident before the loop needs them (with locked memory they then stay).
/// At most 256 KiB.
void prefault_stack(std::size_t bytes = std::size_t{128} * 1024) noexcept;

/// Holds /dev/cpu_dma_latency at a target (0 us: no deep C-states) while alive, which is how
/// the kernel's PM QoS interface is used: the request lasts as long as the file is open.
class CpuDmaLatencyRequest {
 public:
  CpuDmaLatencyRequest() = default;
  ~CpuDmaLatencyRequest() { release(); }
  CpuDmaLatencyRequest(const CpuDmaLatencyRequest&) = delete;
  CpuDmaLatencyRequest& operator=(const CpuDmaLatencyRequest&) = delete;

  /// Not real-time safe. Opens the file and writes the target. Empty string on success,
  /// else a one-line warning (the request is then not held).
  std::string acquire(std::int32_t latency_us = 0);
  /// Closes the file, which ends the request. Idempotent.
  void release() noexcept;
  [[nodiscard]] bool held() const noexcept { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

}  // namespace swivel::rt
