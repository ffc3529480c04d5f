// SPDX-License-Identifier: Apache-2.0
#include "config_watcher.hpp"

#include <poll.h>
#include <sys/inotify.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>

namespace swivel::daemon {
namespace {

using Clock = std::chrono::steady_clock;

// How often the thread looks at its stop token while nothing happens.
constexpr int kIdlePollMs = 100;

}  // namespace

ConfigWatcher::ConfigWatcher(const std::string& file, std::function<void()> on_change,
                             std::chrono::milliseconds debounce)
    : on_change_(std::move(on_change)),
      debounce_(debounce),
      fd_(inotify_init1(IN_NONBLOCK | IN_CLOEXEC)) {
  const auto slash = file.rfind('/');
  directory_ = slash == std::string::npos ? "." : (slash == 0 ? "/" : file.substr(0, slash));
  name_ = slash == std::string::npos ? file : file.substr(slash + 1);
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "inotify_init1");
  if (inotify_add_watch(fd_, directory_.c_str(), IN_CLOSE_WRITE | IN_MOVED_TO | IN_CREATE) < 0) {
    const int error = errno;
    ::close(fd_);
    throw std::system_error(error, std::generic_category(),
                            "inotify cannot watch directory '" + directory_ + "'");
  }
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

ConfigWatcher::~ConfigWatcher() {
  thread_.request_stop();
  if (thread_.joinable()) thread_.join();
  ::close(fd_);
}

void ConfigWatcher::run(const std::stop_token& stop) {
  alignas(inotify_event) char buffer[4096];
  bool pending = false;
  Clock::time_point due{};
  while (!stop.stop_requested()) {
    int timeout_ms = kIdlePollMs;
    if (pending) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(due - Clock::now()).count();
      timeout_ms = static_cast<int>(std::max<long long>(0, std::min<long long>(left, kIdlePollMs)));
    }
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, timeout_ms);
    if (ready > 0) {
      for (;;) {
        const ssize_t n = ::read(fd_, buffer, sizeof buffer);
        if (n <= 0) break;
        for (ssize_t at = 0; at < n;) {
          const auto* event = reinterpret_cast<const inotify_event*>(buffer + at);
          // IN_CREATE alone is not a finished file; it only restarts the quiet period of a
          // write in progress.
          if (event->len > 0 && name_ == event->name &&
              (event->mask & (IN_CLOSE_WRITE | IN_MOVED_TO | IN_CREATE)) != 0) {
            if ((event->mask & IN_CREATE) == 0 || pending) {
              pending = true;
              due = Clock::now() + debounce_;
            }
          }
          at += static_cast<ssize_t>(sizeof(inotify_event) + event->len);
        }
      }
    }
    if (pending && Clock::now() >= due) {
      pending = false;
      on_change_();
    }
  }
}

}  // namespace swivel::daemon
