// SPDX-License-Identifier: Apache-2.0
#pragma once
// A serial port in raw mode (8N1, no flow control, no echo, no line processing) at any baud
// rate: the standard termios rates through cfsetspeed, any other rate (e.g. 3 Mbps on an
// FTDI or 2.25 Mbps) through termios2 with BOTHER. Also works on a pseudo-terminal.
//
// Not real-time: used by the bus thread and off the loop only. The calls block at most for
// the timeouts given.

#include <sys/types.h>

#include <cstdint>
#include <span>
#include <string>

namespace swivel::dynamixel {

class SerialPort {
 public:
  SerialPort() = default;
  ~SerialPort() { close(); }
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  /// Opens `path` in raw mode at `baud` bits/s. @throws std::system_error naming the path.
  void open(const std::string& path, std::uint32_t baud);
  void close() noexcept;
  [[nodiscard]] bool is_open() const noexcept { return fd_ >= 0; }
  [[nodiscard]] int fd() const noexcept { return fd_; }

  /// Writes every byte (waits for room in the driver). False on an error.
  bool write_all(std::span<const std::uint8_t> data) noexcept;
  /// Waits up to `timeout_s` for input; returns the bytes read (0: timeout), -1 on an error.
  ssize_t read_some(std::span<std::uint8_t> buffer, double timeout_s) noexcept;
  /// Drops unread input (stale replies after a timeout).
  void discard_input() noexcept;

  /// The rate the driver reports for an open port (termios2), 0 when it cannot tell.
  [[nodiscard]] std::uint32_t actual_baud() const noexcept;

 private:
  int fd_ = -1;
};

/// Sets `baud` on an open descriptor with termios2 (BOTHER), keeping the other settings.
/// False (errno set) when the driver refuses. Defined apart from <termios.h> users.
bool set_custom_baud(int fd, std::uint32_t baud) noexcept;
/// The output rate termios2 reports, 0 on an error.
std::uint32_t get_baud(int fd) noexcept;

}  // namespace swivel::dynamixel
