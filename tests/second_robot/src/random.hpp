// SPDX-License-Identifier: Apache-2.0
#pragma once
// Seeded streams: splitmix64 to derive a stream's seed, mt19937_64 for the stream, uniform
// and normal deviates computed here (Marsaglia's polar method) so that a spec gives the same
// files with any standard library.

#include <cmath>
#include <cstdint>
#include <random>

namespace swivel::second {

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27U)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31U);
}

class Stream {
 public:
  Stream(std::uint64_t seed, std::uint64_t purpose)
      : engine_(splitmix64(seed * 1315423911ULL + purpose)) {}

  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(engine_() >> 11U) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Integer in [lo, hi].
  int integer(int lo, int hi) {
    return lo + static_cast<int>(uniform() * static_cast<double>(hi - lo + 1));
  }
  bool chance(double p) { return uniform() < p; }
  /// Standard normal deviate.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u = 0.0;
    double v = 0.0;
    double s = 0.0;
    do {
      u = 2.0 * uniform() - 1.0;
      v = 2.0 * uniform() - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double f = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * f;
    has_spare_ = true;
    return u * f;
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

// Stream purposes.
inline constexpr std::uint64_t kScriptStream = 1;
inline constexpr std::uint64_t kStartStream = 2;
inline constexpr std::uint64_t kSensorStream = 3;
inline constexpr std::uint64_t kClockStream = 4;
inline constexpr std::uint64_t kMocapStream = 5;
inline constexpr std::uint64_t kCaseStream = 6;

}  // namespace swivel::second
