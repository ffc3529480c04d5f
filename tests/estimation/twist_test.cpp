// SPDX-License-Identifier: Apache-2.0
// The published twist (StateSnapshot::odometry_twist, RobotState and rt/odom): its noise at
// constant speed, its delay on a ramp and its covariance, measured through the real-time loop
// on the simulated robots. The truth is the simulator's pose, integrated by the simulator.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

#include "fault_rig.hpp"

namespace swivel::estimation {
namespace {

using faults::FaultRig;
using faults::RigOptions;

struct Spread {
  double mean = 0.0;
  double std = 0.0;
};

Spread spread(const std::vector<double>& v) {
  Spread s;
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  double sq = 0.0;
  for (const double x : v) sq += (x - s.mean) * (x - s.mean);
  s.std = std::sqrt(sq / static_cast<double>(v.size() - 1));
  return s;
}

RigOptions docent(double twist_window_s) {
  RigOptions o;
  o.hardware_params = "{sensor_noise: true, motion_capture: false}";
  o.twist_window_s = twist_window_s;
  return o;
}

struct ConstantSpeed {
  Spread vx;
  Spread vy;
  Spread wz;
  double published_sigma_vx = 0.0;  ///< mean sqrt of the published variance
  double published_sigma_wz = 0.0;
};

// Drives `twist` for 1.5 s, then records the published twist over 2 s.
ConstantSpeed constant_speed(const RigOptions& options, double vx, double vy, double wz) {
  FaultRig rig(options);
  rig.drive(vx, vy, wz, 1500);
  std::vector<double> vxs;
  std::vector<double> vys;
  std::vector<double> wzs;
  double sigma_vx = 0.0;
  double sigma_wz = 0.0;
  for (int i = 0; i < 2000; ++i) {
    rig.drive(vx, vy, wz, 1);
    const StateSnapshot s = rig.state();
    EXPECT_EQ(s.fault, FaultCode::kNone);
    vxs.push_back(s.odometry_twist.vx_mps);
    vys.push_back(s.odometry_twist.vy_mps);
    wzs.push_back(s.odometry_twist.wz_radps);
    sigma_vx += std::sqrt(s.twist_covariance[0]);
    sigma_wz += std::sqrt(s.twist_covariance[8]);
  }
  return {spread(vxs), spread(vys), spread(wzs), sigma_vx / 2000.0, sigma_wz / 2000.0};
}

TEST(PublishedTwist, DocentNoiseAtConstantSpeedIsBelowOnePercent) {
  const ConstantSpeed before = constant_speed(docent(0.001), 0.3, 0.0, 0.0);  // one cycle
  const ConstantSpeed after = constant_speed(docent(0.02), 0.3, 0.0, 0.0);    // the default
  std::printf(
      "docent at 0.3 m/s: std(vx) one-cycle difference %.4f m/s, 20 ms window %.5f m/s "
      "(published sigma %.5f m/s); std(wz) %.4f -> %.5f rad/s (published %.5f)\n",
      before.vx.std, after.vx.std, after.published_sigma_vx, before.wz.std, after.wz.std,
      after.published_sigma_wz);
  EXPECT_GT(before.vx.std, 0.03);  // the issue's +-20 %: what the window is measured against
  EXPECT_LT(after.vx.std, 0.003);  // 1 % of the speed
  EXPECT_NEAR(after.vx.mean, 0.3, 1e-3);
}

TEST(PublishedTwist, DocentOnAnArcKeepsYawRateNoiseWithinItsCovariance) {
  // Unequal wheel rates: the two encoders' quantization no longer cancels in the yaw rate.
  const ConstantSpeed before = constant_speed(docent(0.001), 0.3, 0.0, 0.37);
  const ConstantSpeed after = constant_speed(docent(0.02), 0.3, 0.0, 0.37);
  std::printf(
      "docent on an arc (0.3 m/s, 0.37 rad/s): std(vx) %.4f -> %.5f m/s (published "
      "%.5f), std(wz) %.4f -> %.5f rad/s (published %.5f)\n",
      before.vx.std, after.vx.std, after.published_sigma_vx, before.wz.std, after.wz.std,
      after.published_sigma_wz);
  EXPECT_LT(after.vx.std, 0.003);
  EXPECT_NEAR(after.wz.mean, 0.37, 2e-3);
  EXPECT_LT(after.wz.std, 0.2 * before.wz.std);
}

// The covariance's model takes each reading's quantization error as independent. At one
// speed the errors follow a pattern set by the counts per cycle, which the window can see
// (more or less noise than the model says); over speeds the pattern averages out and the
// model is the expectation. Checked on arcs at ten speeds: the mean ratio of the measured
// variance to the published one.
TEST(PublishedTwist, CovarianceMatchesTheSpreadAveragedOverSpeeds) {
  double ratio_vx = 0.0;
  double ratio_wz = 0.0;
  constexpr int kSpeeds = 10;
  for (int i = 0; i < kSpeeds; ++i) {
    const double v = 0.1 + 0.043 * i;
    const ConstantSpeed run = constant_speed(docent(0.02), v, 0.0, 0.9 * v);
    ratio_vx += std::pow(run.vx.std / run.published_sigma_vx, 2) / kSpeeds;
    ratio_wz += std::pow(run.wz.std / run.published_sigma_wz, 2) / kSpeeds;
  }
  std::printf(
      "docent arcs at 0.10-0.49 m/s: measured / published twist variance, mean over "
      "%d speeds: vx %.2f, wz %.2f\n",
      kSpeeds, ratio_vx, ratio_wz);
  EXPECT_GT(ratio_vx, 0.5);
  EXPECT_LT(ratio_vx, 2.0);
  EXPECT_GT(ratio_wz, 0.5);
  EXPECT_LT(ratio_wz, 2.0);
}

TEST(PublishedTwist, SwpcNoiseAtConstantSpeedIsBelowOnePercent) {
  RigOptions o;
  o.robot = "swpc4";
  o.drivetrain = "swpc";
  o.hardware_params = "{sensor_noise: true, motion_capture: false}";
  o.twist_window_s = 0.001;
  const ConstantSpeed before = constant_speed(o, 0.25, 0.1, 0.1);
  o.twist_window_s = 0.02;
  const ConstantSpeed after = constant_speed(o, 0.25, 0.1, 0.1);
  std::printf(
      "swpc4 at (0.25, 0.1) m/s, 0.1 rad/s: std(vx) %.4f -> %.5f m/s (published %.5f), "
      "std(vy) %.4f -> %.5f, std(wz) %.4f -> %.5f rad/s (published %.5f)\n",
      before.vx.std, after.vx.std, after.published_sigma_vx, before.vy.std, after.vy.std,
      before.wz.std, after.wz.std, after.published_sigma_wz);
  EXPECT_LT(after.vx.std, 0.0025);
  EXPECT_LT(after.vy.std, 0.0025);
  EXPECT_NEAR(after.vx.mean, 0.25, 2e-3);
  EXPECT_NEAR(after.vy.mean, 0.1, 2e-3);
  EXPECT_GT(after.published_sigma_vx, 0.0);  // the steering encoders' share included
}

struct Line {
  double t0 = 0.0;  ///< mean time
  double v0 = 0.0;  ///< value at t0
  double slope = 0.0;
};

Line fit_line(const std::vector<double>& t, const std::vector<double>& v, std::size_t first) {
  Line line;
  const auto n = static_cast<double>(t.size() - first);
  line.t0 = std::accumulate(t.begin() + static_cast<long>(first), t.end(), 0.0) / n;
  line.v0 = std::accumulate(v.begin() + static_cast<long>(first), v.end(), 0.0) / n;
  double stt = 0.0;
  double stv = 0.0;
  for (std::size_t k = first; k < t.size(); ++k) {
    stt += (t[k] - line.t0) * (t[k] - line.t0);
    stv += (t[k] - line.t0) * (v[k] - line.v0);
  }
  line.slope = stv / stt;
  return line;
}

// The twist's delay on a ramp: the time by which the published speed trails the true one.
// The truth is the simulator's speed over each cycle (its pose difference), which is the
// ramp's value at the cycle's middle. The one-cycle encoder difference comes from the same
// run's raw wheel angles (StateSnapshot::wheel_angle_rad), so that both see the same
// quantization. Each series is fitted with a line over the ramp (past the first 100 ms, so
// that the window has filled); a delay is the distance between two lines along the time axis.
// Quantization leaves each line's level uncertain by about one count over the ramp (0.5 ms
// against the truth), the one-cycle line more than the smoothed one.
struct RampDelays {
  double window_s = 0.0;     ///< published twist behind the truth
  double one_cycle_s = 0.0;  ///< one-cycle difference behind the truth
  double added_s = 0.0;      ///< published twist behind the one-cycle difference
};

RampDelays ramp_delays(double twist_window_s) {
  RigOptions o = docent(twist_window_s);
  constexpr double kAccel = 0.5;
  o.limits.linear_acceleration_mps2 = kAccel;
  FaultRig rig(o);
  rig.drive(0.0, 0.0, 0.0, 200);
  StateSnapshot last = rig.state();
  std::vector<double> t_true;
  std::vector<double> v_true;
  std::vector<double> t;
  std::vector<double> v_window;
  std::vector<double> v_cycle;
  const double r_m = rig.robot.differential.wheel_radius_left_m;
  for (int i = 0; i < 550; ++i) {  // 0.55 s of a 0.6 s ramp to 0.3 m/s
    rig.drive(0.3, 0.0, 0.0, 1);
    const StateSnapshot s = rig.state();
    const double dt = s.stamp_s - last.stamp_s;
    t_true.push_back(s.stamp_s - 0.5 * dt);
    v_true.push_back(std::hypot(s.truth.x_m - last.truth.x_m, s.truth.y_m - last.truth.y_m) / dt);
    t.push_back(s.stamp_s);
    v_window.push_back(s.odometry_twist.vx_mps);
    v_cycle.push_back(0.5 * r_m *
                      (s.wheel_angle_rad[0] - last.wheel_angle_rad[0] + s.wheel_angle_rad[1] -
                       last.wheel_angle_rad[1]) /
                      dt);
    last = s;
  }
  const Line truth = fit_line(t_true, v_true, 100);
  const Line window = fit_line(t, v_window, 100);
  const Line cycle = fit_line(t, v_cycle, 100);
  EXPECT_NEAR(truth.slope, kAccel, 0.01 * kAccel);
  EXPECT_NEAR(window.slope, kAccel, 0.02 * kAccel);
  const double truth_at_t0 = truth.v0 + truth.slope * (window.t0 - truth.t0);
  RampDelays d;
  d.window_s = (truth_at_t0 - window.v0) / truth.slope;
  d.one_cycle_s = (truth_at_t0 - cycle.v0) / truth.slope;
  d.added_s = (cycle.v0 - window.v0) / truth.slope;
  return d;
}

TEST(PublishedTwist, DelayIsHalfTheWindow) {
  const RampDelays d = ramp_delays(0.02);
  std::printf(
      "twist delay on a 0.5 m/s^2 ramp behind the truth: one-cycle difference %.2f ms, "
      "20 ms window %.2f ms; added by the window %.2f ms\n",
      1e3 * d.one_cycle_s, 1e3 * d.window_s, 1e3 * d.added_s);
  // Theory: the window's centre is 10 ms back, the one-cycle difference's 0.5 ms.
  EXPECT_NEAR(d.window_s, 0.010, 0.0006);
  EXPECT_NEAR(d.one_cycle_s, 0.0005, 0.0006);
  EXPECT_NEAR(d.added_s, 0.0095, 0.0006);
  // The one-cycle window publishes the one-cycle difference.
  EXPECT_NEAR(ramp_delays(0.001).added_s, 0.0, 1e-9);
}
}  // namespace
}  // namespace swivel::estimation
