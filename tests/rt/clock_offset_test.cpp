// SPDX-License-Identifier: Apache-2.0
// ROS time from the loop's monotonic stamps: the measured offset, its conversion, and the
// snapshot's two stamps of one instant, checked against the clocks read by the test itself.

#include "swivel/rt/clock_offset.hpp"

#include <gtest/gtest.h>
#include <time.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "fake_plugins.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::rt {
namespace {

std::int64_t read_ns(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// The test's own view of the offset: realtime read after monotonic, as a plain program would.
// It differs from the bracketed one by about the time one clock read takes.
std::int64_t naive_offset_ns() {
  const std::int64_t mono = read_ns(CLOCK_MONOTONIC);
  const std::int64_t real = read_ns(CLOCK_REALTIME);
  return real - mono;
}

TEST(ClockOffset, BracketedMeasurementAgreesWithTheClocks) {
  const ClockOffsetMeasurement m = measure_clock_offset();
  std::printf("realtime - monotonic offset measured to +-%lld ns\n",
              static_cast<long long>(m.uncertainty_ns));
  EXPECT_GE(m.uncertainty_ns, 0);
  EXPECT_LT(m.uncertainty_ns, 50'000);  // a clock read is well under 100 us
  // The offset is the Unix time of the monotonic epoch (boot): in the past, after 2020.
  EXPECT_GT(m.offset_ns, 1'577'836'800LL * 1'000'000'000);
  EXPECT_LT(m.offset_ns, read_ns(CLOCK_REALTIME));
  EXPECT_NEAR(static_cast<double>(m.offset_ns), static_cast<double>(naive_offset_ns()), 100'000.0);
}

TEST(ClockOffset, MapsAMonotonicStampToRosTime) {
  ClockOffset offset;
  const std::int64_t mono_ns = read_ns(CLOCK_MONOTONIC);
  const std::int64_t real_ns = offset.to_realtime_ns(static_cast<double>(mono_ns) * 1e-9);
  // Through seconds as a double: exact to well under a microsecond at any uptime.
  EXPECT_NEAR(static_cast<double>(real_ns - offset.offset_ns()), static_cast<double>(mono_ns),
              1000.0);
  EXPECT_NEAR(static_cast<double>(real_ns), static_cast<double>(read_ns(CLOCK_REALTIME)), 1e7);
}

TEST(ClockOffset, RosTimeSplitsIntoSecondsAndNanoseconds) {
  const RosTime t = to_ros_time(1'700'000'000'123'456'789LL);
  EXPECT_EQ(t.sec, 1'700'000'000);
  EXPECT_EQ(t.nanosec, 123'456'789U);
  const RosTime before_epoch = to_ros_time(-1);
  EXPECT_EQ(before_epoch.sec, -1);
  EXPECT_EQ(before_epoch.nanosec, 999'999'999U);
}

TEST(ClockOffset, LoopSnapshotCarriesBothStampsOfOneInstant) {
  test::FakeHardware hardware;
  test::FakeDrivetrain drivetrain;
  test::FakeLocalization localization;
  LoopOptions options;
  options.realtime = false;
  options.clock_offset_refresh_s = 0.01;  // the refresh thread runs while the test watches
  ControlLoop loop(options, hardware, drivetrain, localization, "fake_a");
  (void)loop.start();
  std::uint64_t checked = 0;
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
  while (std::chrono::steady_clock::now() < until) {
    const StateSnapshot s = loop.latest();
    if (s.cycle > 0) {
      // Through the offset, within what separates two of its measurements.
      const std::int64_t through_offset =
          std::llround(s.stamp_s * 1e9) + loop.clock_offset().offset_ns();
      EXPECT_NEAR(static_cast<double>(s.ros_stamp_ns), static_cast<double>(through_offset),
                  2.0 * static_cast<double>(loop.clock_offset().uncertainty_ns()) + 1000.0);
      // And against the test's own reading of the two clocks.
      EXPECT_NEAR(static_cast<double>(s.ros_stamp_ns - std::llround(s.stamp_s * 1e9)),
                  static_cast<double>(naive_offset_ns()), 100'000.0);
      ++checked;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  loop.stop();
  EXPECT_GT(checked, 10U);
  // A snapshot is stamped at its cycle: ROS time within a second of the test's clock.
  EXPECT_NEAR(static_cast<double>(loop.latest().ros_stamp_ns),
              static_cast<double>(read_ns(CLOCK_REALTIME)), 1e9);
}

TEST(ClockOffset, LoopRefusesARefreshPeriodThatIsNotPositive) {
  test::FakeHardware hardware;
  test::FakeDrivetrain drivetrain;
  test::FakeLocalization localization;
  LoopOptions options;
  options.clock_offset_refresh_s = 0.0;
  try {
    ControlLoop loop(options, hardware, drivetrain, localization, "fake_a");
    ADD_FAILURE() << "accepted a refresh period of 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "clock_offset_refresh_s must be finite and positive, got 0.000000");
  }
}

}  // namespace
}  // namespace swivel::rt
