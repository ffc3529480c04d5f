// SPDX-License-Identifier: Apache-2.0
#include "swivel/dynamixel/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <system_error>

namespace swivel::dynamixel {
namespace {

// The termios constant of a standard rate, or 0.
speed_t standard_speed(std::uint32_t baud) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 500000: return B500000;
    case 576000: return B576000;
    case 921600: return B921600;
    case 1000000: return B1000000;
    case 1152000: return B1152000;
    case 1500000: return B1500000;
    case 2000000: return B2000000;
    case 2500000: return B2500000;
    case 3000000: return B3000000;
    case 3500000: return B3500000;
    case 4000000: return B4000000;
    default: return 0;
  }
}

[[noreturn]] void fail(const std::string& path, const char* what) {
  throw std::system_error(errno, std::generic_category(), path + ": " + what);
}

}  // namespace

void SerialPort::open(const std::string& path, std::uint32_t baud) {
  close();
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) fail(path, "cannot open");
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) {
    ::close(fd);
    fail(path, "not a serial port");
  }
  cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS | PARENB);
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  const speed_t speed = standard_speed(baud);
  if (speed != 0) cfsetspeed(&tio, speed);
  if (tcsetattr(fd, TCSANOW, &tio) != 0) {
    ::close(fd);
    fail(path, "cannot set raw mode");
  }
  if (speed == 0 && !set_custom_baud(fd, baud)) {
    ::close(fd);
    fail(path, "the driver refuses this baud rate");
  }
  tcflush(fd, TCIOFLUSH);
  fd_ = fd;
}

void SerialPort::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool SerialPort::write_all(std::span<const std::uint8_t> data) noexcept {
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd_, data.data() + done, data.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) {
      pollfd p{fd_, POLLOUT, 0};
      if (poll(&p, 1, 100) < 0 && errno != EINTR) return false;
      continue;
    }
    return false;
  }
  return true;
}

ssize_t SerialPort::read_some(std::span<std::uint8_t> buffer, double timeout_s) noexcept {
  for (;;) {
    const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
    if (n > 0) return n;
    if (n < 0 && errno != EAGAIN && errno != EINTR) return -1;
    if (!(timeout_s > 0.0)) return 0;
    // ppoll for sub-millisecond timeouts.
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(timeout_s);
    ts.tv_nsec = static_cast<long>((timeout_s - static_cast<double>(ts.tv_sec)) * 1e9);
    pollfd p{fd_, POLLIN, 0};
    const int r = ppoll(&p, 1, &ts, nullptr);
    if (r == 0) return 0;
    if (r < 0 && errno != EINTR) return -1;
    if (r > 0 && (p.revents & (POLLERR | POLLNVAL)) != 0) return -1;
    // A hang-up is a device gone (an unplugged USB adapter, a closed pty): an error, not a
    // quiet line that would read as servos not answering.
    if (r > 0 && (p.revents & POLLHUP) != 0 && (p.revents & POLLIN) == 0) return -1;
    timeout_s = 0.0;  // one wait; the caller loops against its own deadline
    if (r > 0 && (p.revents & POLLIN) == 0) return 0;
  }
}

// Not const: it changes the device's state (its input queue), though not this object's.
void SerialPort::discard_input() noexcept {  // NOLINT(readability-make-member-function-const)
  if (fd_ >= 0) tcflush(fd_, TCIFLUSH);
}

std::uint32_t SerialPort::actual_baud() const noexcept { return fd_ >= 0 ? get_baud(fd_) : 0; }

}  // namespace swivel::dynamixel
