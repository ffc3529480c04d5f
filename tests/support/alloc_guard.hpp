// SPDX-License-Identifier: Apache-2.0
#pragma once
// Heap-operation counting for tests, in the spirit of Drake's LimitMalloc: linking
// swivel_test_support replaces the global operator new/delete (every variant) and, in builds
// without AddressSanitizer or ThreadSanitizer (which own malloc themselves), also malloc,
// calloc, realloc, free, aligned_alloc, posix_memalign and memalign (forwarding to glibc's
// __libc_* functions). Only calls made on a thread while it is armed are counted.
//
//   std::thread loop_thread([&] {
//     warm_up();
//     swivel::test::AllocCounter counter;   // arms this thread
//     for (...) loop.run_cycle(t);
//     counts = counter.counts();            // allocations and deallocations seen
//   });

#include <cstddef>
#include <cstdint>

namespace swivel::test {

struct HeapCounts {
  std::uint64_t allocations = 0;    ///< new, malloc, calloc, realloc, aligned allocations
  std::uint64_t deallocations = 0;  ///< delete and free of a non-null pointer
  /// Size of the first allocation counted (0: none); known only to the armed thread.
  std::size_t first_allocation_bytes = 0;
};

/// True when malloc and friends are counted too, not only operator new/delete.
bool malloc_is_counted() noexcept;

/// Arms counting on the constructing thread for its lifetime. Counters are process-wide, so
/// arm one thread at a time; nesting on one thread is not supported.
class AllocCounter {
 public:
  AllocCounter() noexcept;
  ~AllocCounter();
  AllocCounter(const AllocCounter&) = delete;
  AllocCounter& operator=(const AllocCounter&) = delete;
  AllocCounter(AllocCounter&&) = delete;
  AllocCounter& operator=(AllocCounter&&) = delete;

  /// Heap operations on the armed thread since construction. Call it on the armed thread
  /// (first_allocation_bytes is that thread's).
  [[nodiscard]] HeapCounts counts() const noexcept;

 private:
  std::uint64_t allocations_at_start_;
  std::uint64_t deallocations_at_start_;
};

}  // namespace swivel::test
