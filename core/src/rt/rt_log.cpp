// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/rt_log.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>

#include "swivel/rt/state_snapshot.hpp"

namespace swivel::rt {
namespace {

const char* fault_name_of(double value) {
  return fault_code_name(static_cast<FaultCode>(static_cast<int>(value)));
}

}  // namespace

const char* log_code_name(LogCode code) noexcept {
  switch (code) {
    case LogCode::kFaultRaised: return "fault_raised";
    case LogCode::kFaultCleared: return "fault_cleared";
    case LogCode::kCommandRejected: return "command_rejected";
    case LogCode::kMotionCaptureRejected: return "motion_capture_rejected";
    case LogCode::kLocalizationSwapped: return "localization_swapped";
    case LogCode::kZeroSetpointFallback: return "zero_setpoint_fallback";
    case LogCode::kMessage: return "message";
    case LogCode::kLocalizationSwapRefused: return "localization_swap_refused";
    case LogCode::kPoseSet: return "pose_set";
    case LogCode::kPoseRefused: return "pose_refused";
    case LogCode::kClearRefused: return "clear_refused";
  }
  return "unknown";
}

std::string format_log_record(const LogRecord& r) {
  char line[384];
  const auto& v = r.values;
  const auto cycle = static_cast<unsigned long long>(r.cycle);
  const char* text = r.text != nullptr ? r.text : "";
  const bool has_detail = r.detail[0] != '\0';
  int n = 0;
  switch (r.code) {
    case LogCode::kFaultRaised:
      n = std::snprintf(line, sizeof line, "loop cycle %llu t=%.3fs: fault %s (#%.0f)%s%s%s%s%s",
                        cycle, r.stamp_s, fault_name_of(v[0]), v[1], text[0] != '\0' ? ": " : "",
                        text, has_detail ? " (" : "", r.detail.data(), has_detail ? ")" : "");
      if (n > 0 && (v[2] != 0.0 || v[3] != 0.0) && static_cast<std::size_t>(n) < sizeof line) {
        // A measured value against its limit (e.g. the odometry check).
        const int m = std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n),
                                    " [%.4g, limit %.4g]", v[2], v[3]);
        if (m > 0) n += m;
      }
      break;
    case LogCode::kFaultCleared:
      n = std::snprintf(line, sizeof line, "loop cycle %llu t=%.3fs: fault %s cleared", cycle,
                        r.stamp_s, fault_name_of(v[0]));
      break;
    case LogCode::kLocalizationSwapped:
      n = std::snprintf(line, sizeof line,
                        "loop cycle %llu t=%.3fs: localization swapped to %s (swap #%.0f) at "
                        "x=%.4f m y=%.4f m yaw=%.4f rad",
                        cycle, r.stamp_s, r.detail.data(), v[0], v[1], v[2], v[3]);
      break;
    case LogCode::kLocalizationSwapRefused:
      n = std::snprintf(line, sizeof line,
                        "loop cycle %llu t=%.3fs: localization swap refused by the incoming "
                        "plugin's hand-over (%s); the active one stays",
                        cycle, r.stamp_s, r.detail.data());
      break;
    case LogCode::kPoseSet:
      n = std::snprintf(line, sizeof line,
                        "loop cycle %llu t=%.3fs: pose set (request %.0f) to x=%.4f m y=%.4f m "
                        "yaw=%.4f rad",
                        cycle, r.stamp_s, v[0], v[1], v[2], v[3]);
      break;
    case LogCode::kPoseRefused:
      n = std::snprintf(line, sizeof line,
                        "loop cycle %llu t=%.3fs: pose refused (request %.0f) by the "
                        "localization (%s)",
                        cycle, r.stamp_s, v[0], r.detail.data());
      break;
    case LogCode::kClearRefused:
      n = std::snprintf(line, sizeof line,
                        "loop cycle %llu t=%.3fs: clear refused (request %.0f): fault %s "
                        "persists (%s)",
                        cycle, r.stamp_s, v[1], fault_name_of(v[0]), r.detail.data());
      break;
    default:
      n = std::snprintf(line, sizeof line, "loop cycle %llu t=%.3fs: %s: %s%s%s [%g %g %g %g]",
                        cycle, r.stamp_s, log_code_name(r.code), text, has_detail ? " " : "",
                        r.detail.data(), v[0], v[1], v[2], v[3]);
      break;
  }
  if (n < 0) return log_code_name(r.code);
  return {line, std::min(static_cast<std::size_t>(n), sizeof line - 1)};
}

RtLog::RtLog(std::shared_ptr<spdlog::logger> logger) : logger_(std::move(logger)) {}

RtLog::~RtLog() { stop(); }

void RtLog::start(double poll_period_s) {
  if (thread_.joinable()) return;
  const auto period = std::chrono::duration<double>(poll_period_s);
  thread_ = std::jthread([this, period](const std::stop_token& stop) {
    // Polling: the loop must not make the system call that waking a sleeper would need.
    std::mutex mutex;
    std::condition_variable_any wake;
    std::unique_lock lock(mutex);
    while (!stop.stop_requested()) {
      drain();
      wake.wait_for(lock, stop, period, [] { return false; });
    }
    drain();
  });
}

void RtLog::stop() noexcept {
  if (!thread_.joinable()) return;
  thread_.request_stop();
  thread_.join();
}

bool RtLog::push(const LogRecord& record) noexcept {
  if (ring_.try_push(record)) return true;
  dropped_.fetch_add(1, std::memory_order_relaxed);
  return false;
}

std::size_t RtLog::drain() {
  std::size_t written = 0;
  LogRecord record;
  while (ring_.try_pop(record)) {
    write(record);
    ++written;
  }
  const std::uint64_t dropped = dropped_.load(std::memory_order_relaxed);
  if (dropped != dropped_reported_) {
    auto logger = logger_ ? logger_ : spdlog::default_logger();
    logger->warn("loop log ring full: {} records dropped", dropped - dropped_reported_);
    dropped_reported_ = dropped;
  }
  return written;
}

void RtLog::write(const LogRecord& record) {
  auto logger = logger_ ? logger_ : spdlog::default_logger();
  const std::string text = format_log_record(record);
  switch (record.level) {
    case LogLevel::kDebug: logger->debug("{}", text); break;
    case LogLevel::kInfo: logger->info("{}", text); break;
    case LogLevel::kWarn: logger->warn("{}", text); break;
    case LogLevel::kError: logger->error("{}", text); break;
  }
}

}  // namespace swivel::rt
