// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/realtime.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <system_error>

#include "swivel/clock.hpp"

namespace swivel::rt {
namespace {

// std::strerror may share one buffer between threads; the error category does not.
std::string errno_text(int error) { return std::generic_category().message(error); }

}  // namespace

timespec to_timespec(std::int64_t ns) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(ns / kNsPerS);
  ts.tv_nsec = static_cast<long>(ns % kNsPerS);
  return ts;
}

void sleep_until_ns(std::int64_t deadline_ns) noexcept {
  const timespec deadline = to_timespec(deadline_ns);
  // With TIMER_ABSTIME a signal interruption is simply resumed with the same deadline.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
  }
}

std::string make_thread_fifo(int priority) {
  const int min = sched_get_priority_min(SCHED_FIFO);
  const int max = sched_get_priority_max(SCHED_FIFO);
  if (priority < min || priority > max) {
    return "SCHED_FIFO priority " + std::to_string(priority) + " is outside " +
           std::to_string(min) + ".." + std::to_string(max) + "; running SCHED_OTHER";
  }
  sched_param param{};
  param.sched_priority = priority;
  const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (error != 0) {
    return "cannot use SCHED_FIFO priority " + std::to_string(priority) + " (" + errno_text(error) +
           "); running SCHED_OTHER: grant CAP_SYS_NICE or an rtprio limit for real-time timing";
  }
  return {};
}

std::string lock_process_memory() {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    const int error = errno;
    return "cannot lock memory with mlockall (" + errno_text(error) +
           "); page faults may delay the loop: grant CAP_IPC_LOCK or raise the memlock limit";
  }
  return {};
}

void prefault_stack(std::size_t bytes) noexcept {
  // One frame of the full size: every page of it is below the caller's frame, which is the
  // stack the loop will grow into.
  constexpr std::size_t kMaxBytes = std::size_t{256} * 1024;
  volatile unsigned char frame[kMaxBytes];
  const std::size_t n = bytes < kMaxBytes ? bytes : kMaxBytes;
  for (std::size_t i = 0; i < n; i += 4096) frame[kMaxBytes - 1 - i] = 0;
  // Keep the frame (and so the writes) from being optimised away.
  __asm__ __volatile__("" : : "r"(&frame[0]) : "memory");
}

std::string CpuDmaLatencyRequest::acquire(std::int32_t latency_us) {
  release();
  const int fd = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    return "cannot open /dev/cpu_dma_latency (" + errno_text(error) +
           "); CPU idle states may add wake-up latency";
  }
  if (::write(fd, &latency_us, sizeof latency_us) != static_cast<ssize_t>(sizeof latency_us)) {
    const int error = errno;
    ::close(fd);
    return "cannot write /dev/cpu_dma_latency (" + errno_text(error) +
           "); CPU idle states may add wake-up latency";
  }
  fd_ = fd;
  return {};
}

void CpuDmaLatencyRequest::release() noexcept {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

}  // namespace swivel::rt
