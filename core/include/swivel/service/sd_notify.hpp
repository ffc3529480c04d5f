// SPDX-License-Identifier: Apache-2.0
#pragma once
// The systemd notification protocol (sd_notify(3)) spoken directly on $NOTIFY_SOCKET, so
// that the daemon needs no libsystemd: READY=1, RELOADING=1, STOPPING=1, WATCHDOG=1 and
// STATUS=... as one datagram each. Without NOTIFY_SOCKET (not started by systemd) every
// call is a no-op that returns false.
//
// Not real-time safe (a system call per message); call from the daemon's main or health
// thread, never from the loop.

#include <chrono>
#include <optional>
#include <string>
#include <string_view>

namespace swivel::service {

class Notifier {
 public:
  /// Uses $NOTIFY_SOCKET ("/path" or "@abstract"); disabled when unset or empty.
  static Notifier from_environment();

  /// Uses `socket_path` ("/path" or "@abstract"; "" disables).
  /// @throws std::system_error when the socket cannot be created, std::invalid_argument when
  ///         the path does not fit a Unix socket address.
  explicit Notifier(std::string socket_path);
  ~Notifier();
  Notifier(Notifier&& other) noexcept;
  Notifier& operator=(Notifier&& other) noexcept;
  Notifier(const Notifier&) = delete;
  Notifier& operator=(const Notifier&) = delete;

  [[nodiscard]] bool enabled() const { return fd_ >= 0; }
  [[nodiscard]] const std::string& socket_path() const { return path_; }

  /// Sends `state` (newline-separated assignments) as one datagram; true when sent.
  [[nodiscard]] bool notify(std::string_view state) const noexcept;

  /// "READY=1", optionally with "STATUS=<status>".
  [[nodiscard]] bool ready(std::string_view status = {}) const;
  /// "RELOADING=1" with "MONOTONIC_USEC=<now>" (as systemd 253+ expects); follow with
  /// ready() when the reload is done.
  [[nodiscard]] bool reloading(std::string_view status = {}) const;
  /// "STOPPING=1".
  [[nodiscard]] bool stopping(std::string_view status = {}) const;
  /// "WATCHDOG=1": send it only while the daemon is healthy (the loop runs).
  [[nodiscard]] bool watchdog() const noexcept;
  /// "STATUS=<text>" (newlines in `text` are replaced by spaces).
  [[nodiscard]] bool status(std::string_view text) const;

 private:
  std::string path_;
  int fd_ = -1;
};

/// The watchdog interval systemd expects WATCHDOG=1 within: $WATCHDOG_USEC, provided that
/// $WATCHDOG_PID is unset or equals this process. std::nullopt when no watchdog applies or
/// the values are malformed.
std::optional<std::chrono::microseconds> watchdog_interval_from_environment();

/// As watchdog_interval_from_environment, from explicit values (null: unset).
std::optional<std::chrono::microseconds> parse_watchdog_interval(const char* watchdog_usec,
                                                                 const char* watchdog_pid,
                                                                 long own_pid);

}  // namespace swivel::service
