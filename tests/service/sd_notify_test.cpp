// SPDX-License-Identifier: Apache-2.0
#include "swivel/service/sd_notify.hpp"

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace swivel::service {
namespace {

// Plays systemd's part: a datagram socket bound where NOTIFY_SOCKET points.
class FakeSystemd {
 public:
  explicit FakeSystemd(std::string path)
      : path_(std::move(path)), fd_(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0)) {
    if (fd_ < 0) throw std::runtime_error("socket");
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::memcpy(address.sun_path, path_.data(), path_.size());
    auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path_.size() + 1);
    if (path_[0] == '@') {
      address.sun_path[0] = '\0';
      length -= 1;
    }
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&address), length) != 0) {
      throw std::runtime_error("bind " + path_ + ": " + std::strerror(errno));
    }
  }
  FakeSystemd(const FakeSystemd&) = delete;
  FakeSystemd& operator=(const FakeSystemd&) = delete;
  ~FakeSystemd() {
    ::close(fd_);
    if (path_[0] == '/') ::unlink(path_.c_str());
  }

  /// The next datagram, or "<none>" after 5 s.
  [[nodiscard]] std::string receive() const {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 5000) != 1) return "<none>";
    char buffer[4096];
    const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
    return n < 0 ? "<error>" : std::string(buffer, static_cast<std::size_t>(n));
  }

 private:
  std::string path_;
  int fd_ = -1;
};

std::string temp_socket_path() {
  return (std::filesystem::temp_directory_path() /
          ("swivel_notify_" + std::to_string(::getpid()) + ".sock"))
      .string();
}

TEST(SdNotify, SendsTheServiceLifecycleOnAPathSocket) {
  const std::string path = temp_socket_path();
  FakeSystemd systemd(path);
  ::setenv("NOTIFY_SOCKET", path.c_str(), 1);
  const Notifier notifier = Notifier::from_environment();
  ::unsetenv("NOTIFY_SOCKET");
  ASSERT_TRUE(notifier.enabled());

  EXPECT_TRUE(notifier.ready("loop running at 1000 Hz"));
  EXPECT_EQ(systemd.receive(), "READY=1\nSTATUS=loop running at 1000 Hz");
  EXPECT_TRUE(notifier.watchdog());
  EXPECT_EQ(systemd.receive(), "WATCHDOG=1");
  EXPECT_TRUE(notifier.reloading());
  const std::string reloading = systemd.receive();
  EXPECT_EQ(reloading.rfind("RELOADING=1\nMONOTONIC_USEC=", 0), 0U) << reloading;
  EXPECT_GT(std::stoull(reloading.substr(std::strlen("RELOADING=1\nMONOTONIC_USEC="))), 0U);
  EXPECT_TRUE(notifier.ready());
  EXPECT_EQ(systemd.receive(), "READY=1");
  EXPECT_TRUE(notifier.status("two\nlines"));
  EXPECT_EQ(systemd.receive(), "STATUS=two lines");
  EXPECT_TRUE(notifier.stopping());
  EXPECT_EQ(systemd.receive(), "STOPPING=1");
}

TEST(SdNotify, SendsToAnAbstractSocket) {
  const std::string name = "@swivel_notify_test_" + std::to_string(::getpid());
  FakeSystemd systemd(name);
  const Notifier notifier(name);

  EXPECT_TRUE(notifier.ready());
  EXPECT_EQ(systemd.receive(), "READY=1");
}

TEST(SdNotify, IsANoOpWithoutNotifySocket) {
  ::unsetenv("NOTIFY_SOCKET");
  const Notifier notifier = Notifier::from_environment();

  EXPECT_FALSE(notifier.enabled());
  EXPECT_FALSE(notifier.ready());
  EXPECT_FALSE(notifier.watchdog());
}

TEST(SdNotify, ReportsFailureWhenNobodyListens) {
  const Notifier notifier(temp_socket_path() + ".absent");

  EXPECT_TRUE(notifier.enabled());
  EXPECT_FALSE(notifier.ready());
}

TEST(SdNotify, RejectsARelativeSocketPath) {
  try {
    Notifier notifier("run/notify");
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("got 'run/notify'"), std::string::npos) << e.what();
  }
}

TEST(SdNotify, ParsesWatchdogUsecForThisProcessOnly) {
  EXPECT_EQ(parse_watchdog_interval("2000000", nullptr, 42), std::chrono::microseconds(2000000));
  EXPECT_EQ(parse_watchdog_interval("2000000", "42", 42), std::chrono::microseconds(2000000));
  EXPECT_EQ(parse_watchdog_interval("2000000", "43", 42), std::nullopt);
  EXPECT_EQ(parse_watchdog_interval(nullptr, nullptr, 42), std::nullopt);
  EXPECT_EQ(parse_watchdog_interval("0", nullptr, 42), std::nullopt);
  EXPECT_EQ(parse_watchdog_interval("2s", nullptr, 42), std::nullopt);
}

TEST(SdNotify, ReadsWatchdogFromEnvironment) {
  ::setenv("WATCHDOG_USEC", "500000", 1);
  ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
  const auto interval = watchdog_interval_from_environment();
  ::unsetenv("WATCHDOG_USEC");
  ::unsetenv("WATCHDOG_PID");

  EXPECT_EQ(interval, std::chrono::microseconds(500000));
}

}  // namespace
}  // namespace swivel::service
