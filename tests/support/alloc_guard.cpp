// SPDX-License-Identifier: Apache-2.0
#include "alloc_guard.hpp"

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <new>

// Sanitizers interpose malloc themselves; replacing it here too would hand their
// allocations to glibc. There only operator new/delete are counted.
// (g++ defines __SANITIZE_*__; clang answers __has_feature.)
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SWIVEL_ALLOC_GUARD_MALLOC 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define SWIVEL_ALLOC_GUARD_MALLOC 0
#endif
#endif
#ifndef SWIVEL_ALLOC_GUARD_MALLOC
#define SWIVEL_ALLOC_GUARD_MALLOC 1
#endif

#if SWIVEL_ALLOC_GUARD_MALLOC
// glibc's real allocator entry points: reserved names by definition.
// NOLINTBEGIN(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp,readability-identifier-naming)
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* pointer, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* pointer);
}
// NOLINTEND(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp,readability-identifier-naming)
#endif

namespace {

// initial-exec: reading the flag must never itself allocate (as a lazily allocated dynamic
// TLS block could).
__attribute__((tls_model("initial-exec"))) thread_local bool t_armed = false;
__attribute__((tls_model("initial-exec"))) thread_local std::size_t t_first_bytes = 0;

std::atomic<std::uint64_t> g_allocations{0};
std::atomic<std::uint64_t> g_deallocations{0};

void note_allocation(std::size_t bytes) noexcept {
  if (!t_armed) return;
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (t_first_bytes == 0) t_first_bytes = bytes == 0 ? 1 : bytes;
}

void note_deallocation(const void* pointer) noexcept {
  if (t_armed && pointer != nullptr) g_deallocations.fetch_add(1, std::memory_order_relaxed);
}

void* raw_malloc(std::size_t size) noexcept {
#if SWIVEL_ALLOC_GUARD_MALLOC
  return __libc_malloc(size);
#else
  return std::malloc(size);
#endif
}

void* raw_aligned(std::size_t alignment, std::size_t size) noexcept {
#if SWIVEL_ALLOC_GUARD_MALLOC
  return __libc_memalign(alignment, size);
#else
  void* p = nullptr;
  return posix_memalign(&p, alignment, size) == 0 ? p : nullptr;
#endif
}

void raw_free(void* pointer) noexcept {
#if SWIVEL_ALLOC_GUARD_MALLOC
  __libc_free(pointer);
#else
  std::free(pointer);
#endif
}

void* new_impl(std::size_t size, std::size_t alignment, bool nothrow) {
  note_allocation(size);
  if (size == 0) size = 1;
  for (;;) {
    void* p =
        alignment > alignof(std::max_align_t) ? raw_aligned(alignment, size) : raw_malloc(size);
    if (p != nullptr) return p;
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) {
      if (nothrow) return nullptr;
      throw std::bad_alloc();
    }
    handler();
  }
}

void delete_impl(void* pointer) noexcept {
  note_deallocation(pointer);
  raw_free(pointer);
}

}  // namespace

namespace swivel::test {

bool malloc_is_counted() noexcept { return SWIVEL_ALLOC_GUARD_MALLOC != 0; }

AllocCounter::AllocCounter() noexcept
    : allocations_at_start_(g_allocations.load(std::memory_order_relaxed)),
      deallocations_at_start_(g_deallocations.load(std::memory_order_relaxed)) {
  t_first_bytes = 0;
  t_armed = true;
}

AllocCounter::~AllocCounter() { t_armed = false; }

HeapCounts AllocCounter::counts() const noexcept {
  HeapCounts c;
  c.allocations = g_allocations.load(std::memory_order_relaxed) - allocations_at_start_;
  c.deallocations = g_deallocations.load(std::memory_order_relaxed) - deallocations_at_start_;
  c.first_allocation_bytes = t_first_bytes;
  return c;
}

}  // namespace swivel::test

// Replacements of the global allocation functions ([new.delete]).
void* operator new(std::size_t size) { return new_impl(size, 0, false); }
void* operator new[](std::size_t size) { return new_impl(size, 0, false); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return new_impl(size, 0, true);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return new_impl(size, 0, true);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t alignment) {
  return new_impl(size, static_cast<std::size_t>(alignment), false);
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
  return new_impl(size, static_cast<std::size_t>(alignment), false);
}
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  try {
    return new_impl(size, static_cast<std::size_t>(alignment), true);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  try {
    return new_impl(size, static_cast<std::size_t>(alignment), true);
  } catch (...) {
    return nullptr;
  }
}

void operator delete(void* p) noexcept { delete_impl(p); }
void operator delete[](void* p) noexcept { delete_impl(p); }
void operator delete(void* p, std::size_t) noexcept { delete_impl(p); }
void operator delete[](void* p, std::size_t) noexcept { delete_impl(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { delete_impl(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { delete_impl(p); }
void operator delete(void* p, std::align_val_t) noexcept { delete_impl(p); }
void operator delete[](void* p, std::align_val_t) noexcept { delete_impl(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { delete_impl(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { delete_impl(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { delete_impl(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  delete_impl(p);
}

#if SWIVEL_ALLOC_GUARD_MALLOC
// The C allocator, for code (plugins, C libraries) that does not go through operator new.
// Defined in the executable, these take precedence over glibc's for every shared library too.
extern "C" {
void* malloc(std::size_t size) {
  note_allocation(size);
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  note_allocation(count * size);
  return __libc_calloc(count, size);
}
void* realloc(void* pointer, std::size_t size) {
  note_allocation(size);
  return __libc_realloc(pointer, size);
}
void free(void* pointer) {
  note_deallocation(pointer);
  __libc_free(pointer);
}
void* memalign(std::size_t alignment, std::size_t size) {
  note_allocation(size);
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  note_allocation(size);
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0) return EINVAL;
  note_allocation(size);
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr) return ENOMEM;
  *out = p;
  return 0;
}
}
#endif
