#pragma once
// Counts heap allocations made by this process while a guard is alive, so that tests can
// prove a call path is allocation-free (malloc-level, so Eigen and operator new both count).

#include <cstdint>

namespace swivel::test {

class AllocationGuard {
 public:
  AllocationGuard() noexcept;
  ~AllocationGuard();
  AllocationGuard(const AllocationGuard&) = delete;
  AllocationGuard& operator=(const AllocationGuard&) = delete;

  /// Allocations since construction.
  [[nodiscard]] std::uint64_t count() const noexcept;

  /// False in sanitizer builds, whose runtimes own malloc: the counter then sees nothing.
  static bool available() noexcept;

 private:
  std::uint64_t start_ = 0;
};

}  // namespace swivel::test
