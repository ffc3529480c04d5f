// SPDX-License-Identifier: Apache-2.0
// TwistWindow against a drivetrain whose "twist" is three of its channels' rates, so that the
// fit, the covariance and the bookkeeping can be checked against closed forms.

#include "swivel/rt/twist_window.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "swivel/rt/control_loop.hpp"

namespace swivel::rt {
namespace {

// twist = (rate of wheel 0, rate of steering 0, rate of wheel 1): the Jacobian is a selection.
class RatesDrivetrain final : public Drivetrain {
 public:
  int calls = 0;
  void configure(const PluginContext&) override {}
  [[nodiscard]] std::uint32_t module_count() const noexcept override { return 2; }
  Status forward(const HardwareState& a, const HardwareState& b,
                 OdometryIncrement& out) noexcept override {
    ++calls;
    out = OdometryIncrement{};
    out.dt_s = b.stamp_s - a.stamp_s;
    out.twist = {(b.wheel_angle_rad[0] - a.wheel_angle_rad[0]) / out.dt_s,
                 (b.steer_angle_rad[0] - a.steer_angle_rad[0]) / out.dt_s,
                 (b.wheel_angle_rad[1] - a.wheel_angle_rad[1]) / out.dt_s};
    out.valid = true;
    return Status::kOk;
  }
  Status inverse(const Twist2&, const HardwareState&, double, ActuatorCommand&,
                 Twist2&) noexcept override {
    return Status::kError;
  }
  void module_states(std::span<ModuleState>) const noexcept override {}
};

constexpr double kDt = 0.001;

HardwareState reading(double t_s, double wheel0, double wheel1, double steer0) {
  HardwareState r;
  r.stamp_s = t_s;
  r.module_count = 2;
  r.wheel_angle_rad[0] = wheel0;
  r.wheel_angle_rad[1] = wheel1;
  r.steer_angle_rad[0] = steer0;
  return r;
}

TEST(TwistWindow, FitsTheRatesOfLinearAnglesAcrossTheRingsWrap) {
  TwistWindow window({.readings = 21});
  RatesDrivetrain drivetrain;
  for (int k = 0; k < 300; ++k) {  // the ring of 21 wraps many times
    const double t = 1000.0 + k * kDt;
    window.push(reading(t, 50.0 + 4.0 * (t - 1000.0), -2.0 * (t - 1000.0), 0.5 * (t - 1000.0)));
  }
  TwistEstimate out;
  ASSERT_EQ(window.estimate(drivetrain, out), Status::kOk);
  EXPECT_NEAR(out.twist.vx_mps, 4.0, 1e-9);
  EXPECT_NEAR(out.twist.vy_mps, 0.5, 1e-9);
  EXPECT_NEAR(out.twist.wz_radps, -2.0, 1e-9);
  EXPECT_EQ(out.readings, 21U);
  EXPECT_NEAR(out.delay_s, 10 * kDt, 1e-9);
  EXPECT_FALSE(out.has_covariance);  // no resolution given
  EXPECT_EQ(drivetrain.calls, 1);
  EXPECT_NEAR(out.wheel_rate_radps[0], 4.0, 1e-9);
  EXPECT_NEAR(out.wheel_rate_radps[1], -2.0, 1e-9);
  EXPECT_NEAR(out.steer_rate_radps[0], 0.5, 1e-9);
  EXPECT_EQ(out.wheel_rate_radps[2], 0.0);
}

TEST(TwistWindow, CovarianceIsTheQuantizationOfEachFittedRate) {
  const double wheel_q = 2.0 * std::numbers::pi / 4096;
  const double steer_q = 2.0 * std::numbers::pi / 1024;
  TwistWindow window(
      {.readings = 21, .wheel_resolution_rad = wheel_q, .steer_resolution_rad = steer_q});
  RatesDrivetrain drivetrain;
  for (int k = 0; k < 40; ++k) window.push(reading(5.0 + k * kDt, 0.3 * k, 0.1 * k, 0.0));
  TwistEstimate out;
  ASSERT_EQ(window.estimate(drivetrain, out), Status::kOk);
  // Var(slope) = (q^2 / 12) / sum (t - t_c)^2, sum = N (N^2 - 1) / 12 dt^2.
  const double s_tt = 21.0 * (21.0 * 21.0 - 1.0) / 12.0 * kDt * kDt;
  EXPECT_TRUE(out.has_covariance);
  EXPECT_NEAR(out.covariance[0], wheel_q * wheel_q / 12.0 / s_tt, 1e-9 * out.covariance[0]);
  EXPECT_NEAR(out.covariance[4], steer_q * steer_q / 12.0 / s_tt, 1e-9 * out.covariance[4]);
  EXPECT_NEAR(out.covariance[8], wheel_q * wheel_q / 12.0 / s_tt, 1e-9 * out.covariance[8]);
  EXPECT_NEAR(out.covariance[1], 0.0, 1e-12);
  EXPECT_NEAR(out.covariance[5], 0.0, 1e-12);
  // One nominal call and one per channel and module.
  EXPECT_EQ(drivetrain.calls, 1 + 4);
}

TEST(TwistWindow, UnwrapsSteeringThatTheEncoderWraps) {
  TwistWindow window({.readings = 11});
  RatesDrivetrain drivetrain;
  for (int k = 0; k < 11; ++k) {
    const double unwrapped = 3.1 + 3.0 * k * kDt;  // crosses pi half way
    window.push(
        reading(k * kDt + 1.0, 0.0, 0.0, std::remainder(unwrapped, 2.0 * std::numbers::pi)));
  }
  TwistEstimate out;
  ASSERT_EQ(window.estimate(drivetrain, out), Status::kOk);
  EXPECT_NEAR(out.twist.vy_mps, 3.0, 1e-9);
}

TEST(TwistWindow, AReadingThatIsNotLaterStartsAfresh) {
  TwistWindow window({.readings = 11});
  RatesDrivetrain drivetrain;
  for (int k = 0; k < 5; ++k) window.push(reading(1.0 + k * kDt, k, 0.0, 0.0));
  EXPECT_EQ(window.size(), 5U);
  window.push(reading(1.0 + 4 * kDt, 100.0, 0.0, 0.0));  // same stamp as the newest
  EXPECT_EQ(window.size(), 1U);
  TwistEstimate out;
  out.twist.vx_mps = 7.0;
  EXPECT_EQ(window.estimate(drivetrain, out), Status::kError);
  EXPECT_EQ(out.twist.vx_mps, 7.0);  // untouched
  window.push(reading(1.0 + 5 * kDt, 100.5, 0.0, 0.0));
  ASSERT_EQ(window.estimate(drivetrain, out), Status::kOk);
  EXPECT_NEAR(out.twist.vx_mps, 500.0, 1e-6);  // only the two readings since the restart
  window.reset();
  EXPECT_EQ(window.size(), 0U);
}

TEST(TwistWindow, RefusesSizesOutOfRange) {
  EXPECT_THROW(TwistWindow({.readings = 1}), std::invalid_argument);
  EXPECT_THROW(TwistWindow({.readings = kMaxTwistWindowReadings + 1}), std::invalid_argument);
  EXPECT_THROW(TwistWindow({.readings = 5, .wheel_resolution_rad = -1.0}), std::invalid_argument);
}

TEST(TwistWindow, LoopWindowIsItsDurationInPeriodsPlusOne) {
  LoopOptions o;
  o.rate_hz = 1000.0;
  o.twist_window_s = 0.02;
  EXPECT_EQ(twist_window_readings(o), 21U);
  o.twist_window_s = 0.001;
  EXPECT_EQ(twist_window_readings(o), 2U);  // the one-cycle difference
  o.twist_window_s = 0.3;
  try {
    (void)twist_window_readings(o);
    ADD_FAILURE() << "a 300-period window was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "twist_window_s must be finite, positive and at most 255 loop periods, got "
                 "0.300000 s at 1000.000000 Hz");
  }
}

}  // namespace
}  // namespace swivel::rt
