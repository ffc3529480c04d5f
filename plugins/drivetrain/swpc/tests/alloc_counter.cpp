#include "alloc_counter.hpp"

#include <atomic>
#include <cstddef>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SWIVEL_COUNT_ALLOCATIONS 0
#else
#define SWIVEL_COUNT_ALLOCATIONS 1
#endif

// glibc's own entry points; defining malloc & co. here interposes them for the whole test.
#if SWIVEL_COUNT_ALLOCATIONS
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* ptr, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
}
#endif

namespace {
std::atomic<std::uint64_t> g_allocations{0};
std::atomic<int> g_active_guards{0};

[[maybe_unused]] void note() noexcept {
  if (g_active_guards.load(std::memory_order_relaxed) > 0) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
}
}  // namespace

#if SWIVEL_COUNT_ALLOCATIONS
extern "C" {
void* malloc(std::size_t size) {
  note();
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  note();
  return __libc_calloc(count, size);
}
void* realloc(void* ptr, std::size_t size) {
  note();
  return __libc_realloc(ptr, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  note();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  note();
  return __libc_memalign(alignment, size);
}
}
#endif

namespace swivel::test {

AllocationGuard::AllocationGuard() noexcept
    : start_(g_allocations.load(std::memory_order_relaxed)) {
  g_active_guards.fetch_add(1, std::memory_order_relaxed);
}

AllocationGuard::~AllocationGuard() {
  g_active_guards.fetch_sub(1, std::memory_order_relaxed);
}

bool AllocationGuard::available() noexcept {
  return SWIVEL_COUNT_ALLOCATIONS != 0;
}

std::uint64_t AllocationGuard::count() const noexcept {
  return g_allocations.load(std::memory_order_relaxed) - start_;
}

}  // namespace swivel::test
