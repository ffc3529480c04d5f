// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/loop_events.hpp"

namespace swivel::rt {

void LoopEvents::log(LogLevel level, LogCode code, double now_s, const char* text, double a,
                     double b, double c, double d, const char* detail) noexcept {
  LogRecord record;
  record.stamp_s = now_s;
  record.cycle = cycle_;
  record.level = level;
  record.code = code;
  record.text = text != nullptr ? text : "";
  record.values = {a, b, c, d};
  copy_text(detail, record.detail);
  log_.push(record);
}

void LoopEvents::raise(FaultCode code, double now_s, const char* detail, double value,
                       double limit) noexcept {
  cycle_fault_ = code;
  if (latched_ == code) return;  // the same cause persisting is one event
  latched_ = code;
  // A plugin that gives no reason still leaves a cause to show.
  copy_text(detail != nullptr && detail[0] != '\0' ? detail : fault_code_name(code),
            latched_detail_);
  ++fault_count_;
  log(LogLevel::kError, LogCode::kFaultRaised, now_s, "safe stop", static_cast<double>(code),
      static_cast<double>(fault_count_), value, limit, detail);
}

void LoopEvents::raise_transient(FaultCode code, double now_s, const char* text) noexcept {
  // Every rejected command is its own event; a timeout is one event until a command arrives.
  if (transient_ == code && code == FaultCode::kCommandTimeout) return;
  transient_ = code;
  copy_text(text, transient_detail_);
  ++fault_count_;
  log(LogLevel::kWarn, LogCode::kFaultRaised, now_s, text, static_cast<double>(code),
      static_cast<double>(fault_count_));
}

void LoopEvents::clear_latched(double now_s) noexcept {
  log(LogLevel::kInfo, LogCode::kFaultCleared, now_s, "", static_cast<double>(latched_));
  latched_ = FaultCode::kNone;
  latched_detail_[0] = '\0';
}

void LoopEvents::publish(LoopMode mode, StateSnapshot& state) const noexcept {
  state.fault_count = fault_count_;
  if (latched_ != FaultCode::kNone) {
    state.mode = LoopMode::kSafeStop;
    state.fault = latched_;
    state.fault_detail = latched_detail_;
    return;
  }
  state.mode = mode;
  state.fault = transient_;
  if (transient_ == FaultCode::kNone) {
    state.fault_detail[0] = '\0';
  } else {
    state.fault_detail = transient_detail_;
  }
}

}  // namespace swivel::rt
