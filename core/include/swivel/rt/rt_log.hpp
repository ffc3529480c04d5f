// SPDX-License-Identifier: Apache-2.0
#pragma once
// Logging from the real-time loop without formatting on it: the loop pushes fixed-size
// records into an SPSC ring; a logger thread drains them and formats them through spdlog.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "swivel/rt/spsc_ring.hpp"

namespace spdlog {
class logger;
}

namespace swivel::rt {

enum class LogLevel : std::uint8_t { kDebug, kInfo, kWarn, kError };

/// What happened. The values a..d of a record mean what the code says.
enum class LogCode : std::uint16_t {
  kFaultRaised,              ///< a = FaultCode, b = fault count, c/d = measured value and its
                             ///< limit (0 when none); detail = cause
  kFaultCleared,             ///< a = the FaultCode that was cleared
  kCommandRejected,          ///< a = sequence; non-finite velocity command
  kMotionCaptureRejected,    ///< a = sample stamp, s; non-finite motion-capture sample
  kLocalizationSwapped,      ///< a = swap count, b..d = pose handed over (x, y, yaw)
  kZeroSetpointFallback,     ///< inverse kinematics failed or was non-finite: raw zeros written
  kMessage,                  ///< free text only
  kLocalizationSwapRefused,  ///< the incoming localization's hand_over failed; detail = why
  kPoseSet,                  ///< a = request id, b..d = pose set (x, y, yaw)
  kPoseRefused,              ///< a = request id; detail = the localization's reason
  kClearRefused,             ///< a = FaultCode that persists, b = request id; detail = cause
};

/// "fault_raised", ... for messages.
const char* log_code_name(LogCode code) noexcept;

/// One record; trivially copyable so that it crosses the ring by copy.
struct LogRecord {
  double stamp_s = 0.0;  ///< monotonic time of the cycle
  std::uint64_t cycle = 0;
  LogLevel level = LogLevel::kInfo;
  LogCode code = LogCode::kMessage;
  const char* text = "";  ///< must point to static storage (a string literal)
  std::array<double, 4> values{};
  /// Copied text whose lifetime the loop does not control (a plugin's last_error(), whose
  /// library may be unloaded before the logger runs). NUL-terminated, truncated to fit.
  std::array<char, 64> detail{};
};

/// Copies a NUL-terminated string into `out`, truncating. Real-time safe.
template <std::size_t N>
void copy_text(const char* text, std::array<char, N>& out) noexcept {
  std::size_t i = 0;
  if (text != nullptr) {
    for (; i + 1 < N && text[i] != '\0'; ++i) out[i] = text[i];
  }
  out[i] = '\0';
}

/// One line of text for a record (no trailing newline). Not real-time safe.
std::string format_log_record(const LogRecord& record);

/// Owns the ring and the logger thread.
class RtLog {
 public:
  static constexpr std::size_t kCapacity = 256;

  /// `logger` receives the formatted records; null means spdlog's default logger at the time
  /// each record is written.
  explicit RtLog(std::shared_ptr<spdlog::logger> logger = nullptr);
  ~RtLog();
  RtLog(const RtLog&) = delete;
  RtLog& operator=(const RtLog&) = delete;

  /// Not real-time safe. Starts the thread that drains the ring every `poll_period_s`.
  /// Idempotent. @throws std::system_error when the thread cannot be created.
  void start(double poll_period_s = 0.01);

  /// Not real-time safe. Stops the thread after writing every pending record. Idempotent.
  void stop() noexcept;

  /// Producer thread only (the loop). Real-time safe. False (and counted) when the ring is full.
  bool push(const LogRecord& record) noexcept;

  /// Consumer side only: the logger thread, or any one thread while it is not running.
  /// Writes every pending record; returns how many. Not real-time safe.
  std::size_t drain();

  /// Any thread. Records dropped because the ring was full.
  [[nodiscard]] std::uint64_t dropped() const noexcept {
    return dropped_.load(std::memory_order_relaxed);
  }

 private:
  void write(const LogRecord& record);

  SpscRing<LogRecord, kCapacity> ring_;
  std::shared_ptr<spdlog::logger> logger_;
  std::atomic<std::uint64_t> dropped_{0};
  std::uint64_t dropped_reported_ = 0;
  std::jthread thread_;
};

}  // namespace swivel::rt
