// SPDX-License-Identifier: Apache-2.0
// The nominal robots in closed-form situations: encoders, gyro and motion capture against
// what straight runs, turns in place and sideways runs must give, and the controller's limits.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "run_fixtures.hpp"
#include "swivel/independent/simulation.hpp"

namespace swivel::independent {
namespace {

using test::count_rad;
using test::quiet_run;
using test::rows_between;
using test::step_tour;
using test::wrapped;

constexpr double kPi = std::numbers::pi;

TEST(DocentMotion, StraightRunTurnsEncodersByVOverRAndLeavesTheGyroAtZero) {
  RunSpec spec = quiet_run(Robot::kDocent, 12.0, step_tour(2.0, Twist{0.3, 0.0, 0.0}));
  spec.noise.gyro_noise_rad_s = 0.002;
  const RunRecord run = simulate(spec);

  const auto rows = rows_between(run, 3.0, 11.9);  // after the 0.5 s ramp to 0.3 m/s
  const RunRow& first = *rows.front();
  double gyro_sum = 0.0;
  for (const RunRow* r : rows) {
    const double expected = 0.3 / 0.075 * (r->t_s - first.t_s);
    EXPECT_NEAR(r->wheel_rad[0] - first.wheel_rad[0], expected, count_rad()) << "t " << r->t_s;
    EXPECT_NEAR(r->wheel_rad[1] - first.wheel_rad[1], expected, count_rad()) << "t " << r->t_s;
    EXPECT_NEAR(r->truth.x_m - first.truth.x_m, 0.3 * (r->t_s - first.t_s), 1e-9);
    EXPECT_NEAR(r->truth.y_m, 0.0, 1e-12);
    gyro_sum += r->gyro_wz_radps;
  }
  const auto n = static_cast<double>(rows.size());
  EXPECT_NEAR(gyro_sum / n, 0.0, 4.0 * 0.002 / std::sqrt(n));
}

TEST(DocentMotion, TurnInPlaceTurnsTheWheelsOppositeByWBOver2R) {
  RunSpec spec = quiet_run(Robot::kDocent, 12.0, step_tour(2.0, Twist{0.0, 0.0, 0.6}));
  spec.noise.gyro_noise_rad_s = 0.002;
  const RunRecord run = simulate(spec);

  const auto rows = rows_between(run, 3.0, 11.9);
  const RunRow& first = *rows.front();
  const double wheel_rate = 0.6 * 0.40 / 2.0 / 0.075;
  double gyro_sum = 0.0;
  for (const RunRow* r : rows) {
    const double dt = r->t_s - first.t_s;
    EXPECT_NEAR(r->wheel_rad[0] - first.wheel_rad[0], -wheel_rate * dt, count_rad());
    EXPECT_NEAR(r->wheel_rad[1] - first.wheel_rad[1], wheel_rate * dt, count_rad());
    EXPECT_NEAR(wrapped(r->truth.yaw_rad - first.truth.yaw_rad - 0.6 * dt), 0.0, 1e-9);
    EXPECT_NEAR(std::hypot(r->truth.x_m, r->truth.y_m), 0.0, 1e-12);
    gyro_sum += r->gyro_wz_radps;
  }
  const auto n = static_cast<double>(rows.size());
  EXPECT_NEAR(gyro_sum / n, 0.6, 4.0 * 0.002 / std::sqrt(n));
}

TEST(SwpcMotion, SidewaysRunSteersEveryCasterToPlusOrMinus90Degrees) {
  for (const double vy : {0.2, -0.2}) {
    const RunSpec spec = quiet_run(Robot::kSwpc4, 8.0, step_tour(1.5, Twist{0.0, vy, 0.0}));
    const RunRecord run = simulate(spec);
    const double expected = vy > 0.0 ? kPi / 2 : -kPi / 2;
    const auto rows = rows_between(run, 5.0, 7.99);
    for (const RunRow* r : rows) {
      for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_NEAR(wrapped(r->steer_rad[i] - expected), 0.0, 2.0 * count_rad())
            << "vy " << vy << " module " << i + 1 << " t " << r->t_s;
      }
    }
    const RunRow& a = *rows.front();
    const RunRow& b = *rows.back();
    EXPECT_NEAR(b.truth.y_m - a.truth.y_m, vy * (b.t_s - a.t_s), 1e-4);
    // The controller stops steering once the encoder reads 90 degrees: the casters stand
    // within half a count of it, and the travel direction with them.
    EXPECT_NEAR(b.truth.x_m - a.truth.x_m, 0.0, 0.5 * count_rad() * std::abs(vy) * (b.t_s - a.t_s));
    EXPECT_NEAR(b.truth.yaw_rad, 0.0, 1e-4);
  }
}

TEST(SwpcMotion, StraightRunTurnsEveryWheelByVOverR) {
  const RunSpec spec = quiet_run(Robot::kSwpc4, 8.0, step_tour(1.5, Twist{0.25, 0.0, 0.0}));
  const RunRecord run = simulate(spec);
  const auto rows = rows_between(run, 3.0, 7.99);
  const RunRow& first = *rows.front();
  for (const RunRow* r : rows) {
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_NEAR(r->wheel_rad[i] - first.wheel_rad[i], 0.25 / 0.055 * (r->t_s - first.t_s),
                  count_rad());
      EXPECT_EQ(r->steer_rad[i], 0.0);
    }
  }
}

// Body velocity and yaw rate from motion capture by central differences; then the largest
// change per second over 0.1 s.
struct PeakAccelerations {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
};

PeakAccelerations peak_accelerations_from_motion_capture(const RunRecord& run) {
  const auto& rows = run.rows;
  std::vector<std::array<double, 3>> v(rows.size(), {0.0, 0.0, 0.0});
  for (std::size_t k = 1; k + 1 < rows.size(); ++k) {
    const Pose& a = rows[k - 1].truth;
    const Pose& b = rows[k + 1].truth;
    const double dt = rows[k + 1].t_s - rows[k - 1].t_s;
    const double yaw = rows[k].truth.yaw_rad;
    const double dx = (b.x_m - a.x_m) / dt;
    const double dy = (b.y_m - a.y_m) / dt;
    v[k] = {std::cos(yaw) * dx + std::sin(yaw) * dy, -std::sin(yaw) * dx + std::cos(yaw) * dy,
            wrapped(b.yaw_rad - a.yaw_rad) / dt};
  }
  PeakAccelerations peak;
  constexpr std::size_t kSpan = 5;
  for (std::size_t k = kSpan + 1; k + kSpan + 1 < rows.size(); ++k) {
    const double dt = rows[k + kSpan].t_s - rows[k - kSpan].t_s;
    peak.x = std::max(peak.x, std::abs(v[k + kSpan][0] - v[k - kSpan][0]) / dt);
    peak.y = std::max(peak.y, std::abs(v[k + kSpan][1] - v[k - kSpan][1]) / dt);
    peak.yaw = std::max(peak.yaw, std::abs(v[k + kSpan][2] - v[k - kSpan][2]) / dt);
  }
  return peak;
}

TEST(Controller, DocentBodyNeverAcceleratesBeyondTheLimitsYetReachesThem) {
  RunSpec spec =
      quiet_run(Robot::kDocent, 20.0,
                {TourSegment{0.0, 0.0, Twist{}}, TourSegment{2.0, 0.0, {0.4, 0.0, 0.0}},
                 TourSegment{5.0, 0.0, {-0.2, 0.0, 0.0}}, TourSegment{8.0, 0.0, {0.0, 0.0, 0.0}},
                 TourSegment{10.0, 0.0, {0.0, 0.0, 0.9}}, TourSegment{13.0, 0.0, {0.0, 0.0, -0.9}},
                 TourSegment{16.0, 0.0, {0.0, 0.0, 0.0}}});
  spec.truth.linear_accel_limit_mps2 = 0.3;
  spec.truth.angular_accel_limit_radps2 = 1.0;
  const PeakAccelerations peak = peak_accelerations_from_motion_capture(simulate(spec));
  EXPECT_LE(peak.x, 0.3 * 1.01);
  EXPECT_GE(peak.x, 0.3 * 0.95);
  EXPECT_LE(peak.yaw, 1.0 * 1.01);
  EXPECT_GE(peak.yaw, 1.0 * 0.95);
}

TEST(Controller, SwpcBodyNeverAcceleratesBeyondTheLinearLimitYetReachesIt) {
  const RunSpec spec =
      quiet_run(Robot::kSwpc4, 12.0,
                {TourSegment{0.0, 0.0, Twist{}}, TourSegment{1.5, 0.0, {0.3, 0.0, 0.0}},
                 TourSegment{4.0, 0.0, {0.1, 0.0, 0.0}}, TourSegment{7.0, 0.0, {0.0, 0.0, 0.0}}});
  const PeakAccelerations peak = peak_accelerations_from_motion_capture(simulate(spec));
  EXPECT_LE(peak.x, 0.6 * 1.01);
  EXPECT_GE(peak.x, 0.6 * 0.95);
  EXPECT_LE(peak.y, 1e-6);
}

TEST(Controller, SteeringRatesStayWithinTheRobotsLimit) {
  RunSpec spec =
      quiet_run(Robot::kSwpc4, 14.0,
                {TourSegment{0.0, 0.0, Twist{}}, TourSegment{1.5, 0.0, {0.0, 0.2, 0.0}},
                 TourSegment{5.5, 0.0, {0.2, 0.0, 0.0}}, TourSegment{9.5, 0.0, {0.0, 0.0, 0.5}}});
  spec.truth.steering_rate_limit_radps = 1.0;
  const RunRecord run = simulate(spec);
  double peak = 0.0;
  constexpr std::size_t kSpan = 10;  // 0.1 s: one count of quantization is 0.015 rad/s
  for (std::size_t k = kSpan; k < run.rows.size(); ++k) {
    const RunRow& a = run.rows[k - kSpan];
    const RunRow& b = run.rows[k];
    for (std::size_t i = 0; i < 4; ++i) {
      peak = std::max(peak, std::abs(b.steer_rad[i] - a.steer_rad[i]) / (b.t_s - a.t_s));
    }
  }
  EXPECT_LE(peak, 1.0 + 2.0 * count_rad() / 0.1);
  EXPECT_GE(peak, 0.95);
}

// Passive casters trail the motion at the angle the no-lateral-slip law gives with the true
// caster offset: sin(alpha - phi) = d w / |v_s|.
TEST(SelfAligning, CastersSettleAtTheNoSlipAngleOfTheTrueCasterOffset) {
  RunSpec spec = quiet_run(Robot::kSwpc4, 10.0, step_tour(1.5, Twist{0.2, 0.0, 0.5}));
  spec.steering = Steering::kSelfAligning;
  spec.truth.caster_offset_scale = {1.5, 1.5, 1.5, 1.5};
  const RunRecord run = simulate(spec);
  const std::array<std::array<double, 2>, 4> axes{
      {{0.215, 0.125}, {0.215, -0.125}, {-0.215, -0.125}, {-0.215, 0.125}}};
  double largest_gap_to_nominal = 0.0;
  for (const RunRow* r : rows_between(run, 8.0, 10.0)) {
    for (std::size_t i = 0; i < 4; ++i) {
      const double sx = 0.2 - 0.5 * axes[i][1];
      const double sy = 0.5 * axes[i][0];
      const double alpha = std::atan2(sy, sx);
      const double speed = std::hypot(sx, sy);
      const double with_true_d = alpha - std::asin(0.030 * 0.5 / speed);
      const double with_nominal_d = alpha - std::asin(0.020 * 0.5 / speed);
      EXPECT_NEAR(wrapped(r->steer_rad[i] - with_true_d), 0.0, 2.0 * count_rad())
          << "module " << i + 1;
      largest_gap_to_nominal =
          std::max(largest_gap_to_nominal, std::abs(r->steer_rad[i] - with_nominal_d));
    }
  }
  EXPECT_GT(largest_gap_to_nominal, 10.0 * count_rad());
}

TEST(SelfAligning, PassiveRobotFollowsTheCommandWhenNothingIsWrong) {
  RunSpec spec =
      quiet_run(Robot::kSwpc4, 12.0,
                {TourSegment{0.0, 0.0, Twist{}}, TourSegment{1.5, 0.0, {0.2, 0.0, 0.5}},
                 TourSegment{4.0, 0.0, {0.0, 0.0, -0.6}}, TourSegment{7.0, 0.0, {0.15, 0.1, 0.0}},
                 TourSegment{10.0, 0.0, {0.0, 0.0, 0.0}}});
  spec.steering = Steering::kSelfAligning;
  const RunRecord run = simulate(spec);
  // The true twist matches the command once the limiter's ramps are over.
  for (const double t : {3.5, 6.5, 9.5}) {
    const RunRow& r = test::row_at(run, t);
    EXPECT_NEAR(r.true_twist.vx_mps, r.cmd.vx_mps, 2e-3) << "t " << t;
    EXPECT_NEAR(r.true_twist.vy_mps, r.cmd.vy_mps, 2e-3) << "t " << t;
    EXPECT_NEAR(r.true_twist.wz_radps, r.cmd.wz_radps, 5e-3) << "t " << t;
  }
}

// The random-walk slip: two wheels slipping independently with sigma 0.2 % turn a docent
// driving straight at v by v (s_R - s_L) / b, whose RMS is v sqrt(2) sigma / b.
TEST(Slip, RandomWalkSlipHasItsDocumentedSize) {
  RunSpec spec = quiet_run(Robot::kDocent, 300.0, step_tour(1.0, Twist{0.4, 0.0, 0.0}));
  spec.noise.slip_std = 0.002;
  double sum_sq = 0.0;
  double n = 0.0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    spec.seed = seed;
    const RunRecord run = simulate(spec);
    for (const RunRow* r : rows_between(run, 3.0, 300.0)) {
      sum_sq += r->true_twist.wz_radps * r->true_twist.wz_radps;
      n += 1.0;
    }
  }
  const double expected = 0.4 * std::sqrt(2.0) * 0.002 / 0.40;
  EXPECT_NEAR(std::sqrt(sum_sq / n), expected, 0.3 * expected);
}

}  // namespace
}  // namespace swivel::independent
