// SPDX-License-Identifier: Apache-2.0
#include "swivel/service/sd_notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "swivel/clock.hpp"

namespace swivel::service {

namespace {

std::string with_status(std::string state, std::string_view status) {
  if (!status.empty()) {
    state += "\nSTATUS=";
    for (const char c : status) state += c == '\n' ? ' ' : c;
  }
  return state;
}

bool parse_u64(const char* text, unsigned long long& value) {
  if (text == nullptr || *text == '\0') return false;
  const char* end = text + std::strlen(text);
  const auto result = std::from_chars(text, end, value);
  return result.ec == std::errc() && result.ptr == end;
}

}  // namespace

Notifier Notifier::from_environment() {
  const char* path = std::getenv("NOTIFY_SOCKET");
  return Notifier(path != nullptr ? path : "");
}

Notifier::Notifier(std::string socket_path) : path_(std::move(socket_path)) {
  if (path_.empty()) return;
  if (path_.size() >= sizeof(sockaddr_un::sun_path) || (path_[0] != '/' && path_[0] != '@')) {
    throw std::invalid_argument("NOTIFY_SOCKET: expected an absolute path or @name of at most " +
                                std::to_string(sizeof(sockaddr_un::sun_path) - 1) +
                                " characters, got '" + path_ + "'");
  }
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "socket(AF_UNIX)");
}

Notifier::~Notifier() {
  if (fd_ >= 0) ::close(fd_);
}

Notifier::Notifier(Notifier&& other) noexcept
    : path_(std::move(other.path_)), fd_(std::exchange(other.fd_, -1)) {}

Notifier& Notifier::operator=(Notifier&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(other.path_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

bool Notifier::notify(std::string_view state) const noexcept {
  if (fd_ < 0) return false;
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path_.data(), path_.size());
  // An abstract socket's name starts with a NUL byte and is not NUL-terminated.
  if (path_[0] == '@') address.sun_path[0] = '\0';
  const auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path_.size() +
                                             (path_[0] == '@' ? 0 : 1));
  const ssize_t sent = ::sendto(fd_, state.data(), state.size(), MSG_NOSIGNAL,
                                reinterpret_cast<const sockaddr*>(&address), length);
  return sent == static_cast<ssize_t>(state.size());
}

bool Notifier::ready(std::string_view status) const {
  return notify(with_status("READY=1", status));
}

bool Notifier::reloading(std::string_view status) const {
  const auto usec = static_cast<unsigned long long>(monotonic_ns() / 1000);
  return notify(with_status("RELOADING=1\nMONOTONIC_USEC=" + std::to_string(usec), status));
}

bool Notifier::stopping(std::string_view status) const {
  return notify(with_status("STOPPING=1", status));
}

bool Notifier::watchdog() const noexcept { return notify("WATCHDOG=1"); }

bool Notifier::status(std::string_view text) const {
  std::string state = "STATUS=";
  for (const char c : text) state += c == '\n' ? ' ' : c;
  return notify(state);
}

std::optional<std::chrono::microseconds> parse_watchdog_interval(const char* watchdog_usec,
                                                                 const char* watchdog_pid,
                                                                 long own_pid) {
  unsigned long long usec = 0;
  if (!parse_u64(watchdog_usec, usec) || usec == 0) return std::nullopt;
  if (watchdog_pid != nullptr && *watchdog_pid != '\0') {
    // The watchdog is meant for another process (e.g. the one that forked us).
    unsigned long long pid = 0;
    if (!parse_u64(watchdog_pid, pid) || pid != static_cast<unsigned long long>(own_pid)) {
      return std::nullopt;
    }
  }
  return std::chrono::microseconds(static_cast<std::chrono::microseconds::rep>(usec));
}

std::optional<std::chrono::microseconds> watchdog_interval_from_environment() {
  return parse_watchdog_interval(std::getenv("WATCHDOG_USEC"), std::getenv("WATCHDOG_PID"),
                                 static_cast<long>(::getpid()));
}

}  // namespace swivel::service
