// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's faults and log events, shared by its stages. A stage that finds a fault raises
// it here; the loop reads the result to choose the mode and publishes it. Two kinds:
//  - latched (kSafeStop): stays until cleared; the same cause raised again in later cycles is
//    one event. cycle_fault() says whether one was raised in the cycle under way, which a
//    clear waits for;
//  - transient (a command timeout, a rejected command, a cancelled calibration): stays until
//    a fresh command or a clear; every rejected command is an event of its own, a timeout
//    one until a command arrives.
// Each event is counted (fault_count()) and logged through RtLog, stamped with the cycle
// begin_cycle() named.
//
// Loop thread only. Real-time safe: no allocation, no lock, no formatting; noexcept.

#include <cstdint>

#include "swivel/rt/rt_log.hpp"
#include "swivel/rt/state_snapshot.hpp"

namespace swivel::rt {

class LoopEvents {
 public:
  explicit LoopEvents(RtLog& log) noexcept : log_(log) {}

  /// At the start of every cycle: `cycle` stamps its log records; no fault raised yet.
  void begin_cycle(std::uint64_t cycle) noexcept {
    cycle_ = cycle;
    cycle_fault_ = FaultCode::kNone;
  }

  /// Pushes one record (`text` static; `detail` copied, may be null).
  void log(LogLevel level, LogCode code, double now_s, const char* text, double a = 0.0,
           double b = 0.0, double c = 0.0, double d = 0.0, const char* detail = nullptr) noexcept;

  /// A latched fault with its cause (`detail`, copied; the code's name when empty) and the
  /// measured value against its limit (0 when none).
  void raise(FaultCode code, double now_s, const char* detail, double value = 0.0,
             double limit = 0.0) noexcept;

  /// A transient fault with its cause (`text`, static).
  void raise_transient(FaultCode code, double now_s, const char* text) noexcept;

  /// Leaves the latched fault (logged).
  void clear_latched(double now_s) noexcept;

  /// Leaves the transient fault.
  void clear_transient() noexcept { transient_ = FaultCode::kNone; }

  [[nodiscard]] FaultCode latched() const noexcept { return latched_; }
  [[nodiscard]] bool any_latched() const noexcept { return latched_ != FaultCode::kNone; }
  [[nodiscard]] const FaultDetail& latched_detail() const noexcept { return latched_detail_; }
  [[nodiscard]] FaultCode transient() const noexcept { return transient_; }
  [[nodiscard]] const FaultDetail& transient_detail() const noexcept { return transient_detail_; }
  /// The latched fault raised in the cycle under way, kNone when none was.
  [[nodiscard]] FaultCode cycle_fault() const noexcept { return cycle_fault_; }
  /// Fault events so far.
  [[nodiscard]] std::uint64_t fault_count() const noexcept { return fault_count_; }

  /// The snapshot's mode, fault and fault count: kSafeStop with the latched fault, else `mode`
  /// with the transient fault.
  void publish(LoopMode mode, StateSnapshot& state) const noexcept;

 private:
  RtLog& log_;
  std::uint64_t cycle_ = 0;
  std::uint64_t fault_count_ = 0;
  FaultCode latched_ = FaultCode::kNone;    // kSafeStop cause
  FaultCode transient_ = FaultCode::kNone;  // command timeout / rejected command
  FaultCode cycle_fault_ = FaultCode::kNone;
  FaultDetail latched_detail_{};
  FaultDetail transient_detail_{};
};

}  // namespace swivel::rt
