// SPDX-License-Identifier: Apache-2.0
#pragma once
// The rate the bridge's publisher really reached, against the rate it could have: the
// configured dds.publish_rate_hz, or the loop's own cycle rate when the loop runs slower
// (the publisher sends loop cycles, never the same one twice). Measured over windows of a
// couple of seconds; a window short by more than kShortfallTolerance is a shortfall. Plain
// arithmetic on the publisher thread; no clock of its own, so that tests drive it.

#include <cstdint>

namespace swivel::dds {

class PublishRateMeter {
 public:
  /// A shortfall: the achieved rate below the attainable one by more than this fraction.
  static constexpr double kShortfallTolerance = 0.05;

  /// Windows after a reported change in which no other is reported: a rate near the
  /// tolerance would otherwise fall short and recover every few windows (one log line a
  /// minute at most with 2 s windows); short_of_rate() follows every window all the same.
  static constexpr int kQuietWindows = 29;

  enum class Change { kNone, kFellShort, kRecovered };

  explicit PublishRateMeter(double configured_hz, double window_s = 2.0);

  /// At monotonic time `now_s`, `published` states written so far, the loop's newest cycle
  /// `cycle` (0 while there is none). Returns how the reported verdict changed when a
  /// window closed (kQuietWindows apart at least).
  Change update(double now_s, std::uint64_t published, std::uint64_t cycle);

  [[nodiscard]] double configured_hz() const { return configured_hz_; }
  /// States written per second over the last complete window; 0 before the first.
  [[nodiscard]] double achieved_hz() const { return achieved_hz_; }
  /// min(configured, the loop's cycles per second) over the same window.
  [[nodiscard]] double attainable_hz() const { return attainable_hz_; }
  /// The last complete window fell short.
  [[nodiscard]] bool short_of_rate() const { return short_; }

 private:
  double configured_hz_;
  double window_s_;
  bool open_ = false;  ///< a window has started (at a known cycle)
  double start_s_ = 0.0;
  std::uint64_t start_published_ = 0;
  std::uint64_t start_cycle_ = 0;
  double achieved_hz_ = 0.0;
  double attainable_hz_ = 0.0;
  bool short_ = false;
  bool reported_short_ = false;  ///< the last change returned was kFellShort
  int quiet_windows_ = 0;        ///< windows left before another change is reported
};

}  // namespace swivel::dds
