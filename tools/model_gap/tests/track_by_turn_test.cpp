// SPDX-License-Identifier: Apache-2.0
// A left/right wheel-radius difference from tracks fitted alone on runs turning at different
// radii (track_by_turn.hpp): the turn radius each run is weighed at, and the straight-line fit
// of the tracks against it, checked on made-up runs and tracks drawn here.

#include "swivel/model_gap/track_by_turn.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace swivel::model_gap {
namespace {

RobotModel differential_robot() {
  RobotModel m;
  m.drivetrain = DrivetrainKind::kDifferential;
  m.differential = {0.05, 0.05, 0.4};
  return m;
}

// A run at 20 Hz driving at v (m/s) and w (rad/s), then the same time turning on the spot.
RunData run_at(double v, double w, double spot_w, double seconds) {
  const RobotModel m = differential_robot();
  const DifferentialParams& p = m.differential;
  RunData run;
  run.wheel_rad.assign(2, {});
  double left = 0.0;
  double right = 0.0;
  const double dt = 0.05;
  for (int k = 0; k * dt <= 2.0 * seconds; ++k) {
    run.t_s.push_back(k * dt);
    run.wheel_rad[0].push_back(left);
    run.wheel_rad[1].push_back(right);
    const bool driving = k * dt < seconds;
    const double vv = driving ? v : 0.0;
    const double ww = driving ? w : spot_w;
    left += dt * (vv - 0.5 * ww * p.track_width_m) / p.wheel_radius_left_m;
    right += dt * (vv + 0.5 * ww * p.track_width_m) / p.wheel_radius_right_m;
  }
  return run;
}

TEST(TrackByTurn, ARunIsWeighedAtTheRadiusItTurnsAt) {
  const RobotModel m = differential_robot();
  // A circle of 0.5 m turning left, then right, and turns on the spot.
  EXPECT_NEAR(turn_radius_m(m, run_at(0.2, 0.4, 0.4, 20.0), 1.0), 0.25, 0.01);
  EXPECT_NEAR(turn_radius_m(m, run_at(0.2, 0.4, 0.0, 20.0), 1.0), 0.5, 1e-9);
  EXPECT_NEAR(turn_radius_m(m, run_at(0.2, -0.4, 0.0, 20.0), 1.0), -0.5, 1e-9);
  EXPECT_NEAR(turn_radius_m(m, run_at(0.0, 0.0, 0.5, 20.0), 1.0), 0.0, 1e-12);
  EXPECT_TRUE(std::isnan(turn_radius_m(m, run_at(0.2, 0.0, 0.0, 20.0), 1.0)));
  RobotModel swpc = m;
  swpc.drivetrain = DrivetrainKind::kSwpc;
  EXPECT_TRUE(std::isnan(turn_radius_m(swpc, run_at(0.2, 0.4, 0.0, 20.0), 1.0)));
}

// Tracks of runs at these radii, as a robot with track scale s0 and radius difference e
// shows them (s = s0 - 2 R e / b), with noise of `sigma`.
std::vector<double> tracks_of(const std::vector<double>& radii, double s0, double e, double b,
                              double sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<double> out;
  out.reserve(radii.size());
  for (const double r : radii) out.push_back(s0 - 2.0 * r * e / b + noise(rng));
  return out;
}

TEST(TrackByTurn, CirclesBothWaysRoundFixTheRadiusDifferenceWithAnHonestSigma) {
  const std::vector<double> radii = {-0.8, -0.8, -0.3, -0.3, -0.3, 0.0, 0.3, 0.3, 0.8, 0.8};
  const std::vector<double> sigmas(radii.size(), 0.002);
  const double s0 = 1.012;
  const double e = -0.0007;
  std::mt19937_64 rng(11);
  int within_1 = 0;
  int within_3 = 0;
  double chi_square = 0.0;
  const int draws = 400;
  for (int d = 0; d < draws; ++d) {
    const TrackByTurn t =
        fit_track_by_turn(tracks_of(radii, s0, e, 0.4, 0.002, rng), sigmas, radii, 0.4);
    ASSERT_TRUE(t.fitted);
    const double z = (t.radius_difference - e) / t.radius_difference_sigma;
    within_1 += std::abs(z) <= 1.0 ? 1 : 0;
    within_3 += std::abs(z) <= 3.0 ? 1 : 0;
    EXPECT_LE(std::abs(t.track_scale - s0), 5.0 * t.track_scale_sigma);
    chi_square += t.chi_square;
  }
  // A normal deviate: 68.3 % within 1 sigma, 99.7 % within 3; chi^2 averages its dof (8).
  EXPECT_NEAR(within_1 / static_cast<double>(draws), 0.683, 0.07);
  EXPECT_GE(within_3 / static_cast<double>(draws), 0.98);
  EXPECT_NEAR(chi_square / draws, 8.0, 0.8);
}

TEST(TrackByTurn, CirclesOneWayRoundCannotTellItFromTheTrack) {
  const std::vector<double> radii = {0.3, 0.3, 0.8, 0.8, 0.0, -0.3};
  const std::vector<double> scales = {1.01, 1.011, 1.012, 1.013, 1.009, 1.008};
  const TrackByTurn t = fit_track_by_turn(scales, std::vector<double>(6, 0.002), radii, 0.4);
  EXPECT_FALSE(t.fitted);  // one run turning right
  EXPECT_EQ(t.runs, 6U);
}

}  // namespace
}  // namespace swivel::model_gap
