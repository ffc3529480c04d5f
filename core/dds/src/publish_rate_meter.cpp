// SPDX-License-Identifier: Apache-2.0
#include "swivel/dds/publish_rate_meter.hpp"

#include <algorithm>

namespace swivel::dds {

PublishRateMeter::PublishRateMeter(double configured_hz, double window_s)
    : configured_hz_(configured_hz), window_s_(window_s) {}

PublishRateMeter::Change PublishRateMeter::update(double now_s, std::uint64_t published,
                                                  std::uint64_t cycle) {
  // A window starts at a known cycle: before the loop's first one there is nothing to send.
  if (!open_ || cycle < start_cycle_) {
    open_ = cycle != 0;
    start_s_ = now_s;
    start_published_ = published;
    start_cycle_ = cycle;
    return Change::kNone;
  }
  const double elapsed_s = now_s - start_s_;
  if (elapsed_s < window_s_) return Change::kNone;
  achieved_hz_ = static_cast<double>(published - start_published_) / elapsed_s;
  const double loop_hz = static_cast<double>(cycle - start_cycle_) / elapsed_s;
  attainable_hz_ = std::min(configured_hz_, loop_hz);
  start_s_ = now_s;
  start_published_ = published;
  start_cycle_ = cycle;
  short_ = achieved_hz_ < (1.0 - kShortfallTolerance) * attainable_hz_;
  if (quiet_windows_ > 0) {
    --quiet_windows_;
    return Change::kNone;
  }
  if (short_ == reported_short_) return Change::kNone;
  reported_short_ = short_;
  quiet_windows_ = kQuietWindows;
  return short_ ? Change::kFellShort : Change::kRecovered;
}

}  // namespace swivel::dds
