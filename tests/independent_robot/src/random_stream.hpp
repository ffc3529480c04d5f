// SPDX-License-Identifier: Apache-2.0
#pragma once
// Seeded random numbers, one independent stream per purpose (tour, process noise, sensor
// noise, clocks) so that changing one part of a run leaves the others' draws unchanged.
// Gaussians come from Box-Muller on the engine's raw bits, not from std::normal_distribution,
// whose output differs between standard libraries.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace swivel::independent {

class RandomStream {
 public:
  RandomStream(std::uint64_t seed, std::uint64_t salt) : engine_(mix(seed ^ mix(salt))) {}

  /// Uniform in [0, 1).
  double uniform() {
    constexpr double kScale = 1.0 / 9007199254740992.0;  // 2^-53
    return static_cast<double>(engine_() >> 11U) * kScale;
  }

  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

  /// Uniform integer in [lo, hi].
  int integer(int lo, int hi) {
    const auto span = static_cast<double>(hi - lo + 1);
    const int k = lo + static_cast<int>(std::floor(uniform() * span));
    return k > hi ? hi : k;
  }

  double gaussian() {
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

  double exponential(double mean) { return -mean * std::log(1.0 - uniform()); }

  bool chance(double p) { return uniform() < p; }

 private:
  // splitmix64's finaliser: nearby seeds give unrelated engine states.
  static std::uint64_t mix(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ULL;
    x = (x ^ (x >> 30U)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27U)) * 0x94D049BB133111EBULL;
    return x ^ (x >> 31U);
  }

  std::mt19937_64 engine_;
};

/// Salts of the streams a run uses.
inline constexpr std::uint64_t kTourStream = 1;
inline constexpr std::uint64_t kStartStream = 2;
inline constexpr std::uint64_t kProcessStream = 3;
inline constexpr std::uint64_t kSensorStream = 4;
inline constexpr std::uint64_t kClockStream = 5;
inline constexpr std::uint64_t kOutsideStream = 6;

}  // namespace swivel::independent
