// SPDX-License-Identifier: Apache-2.0
#include "swivel/calibration/calibration_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "test_robots.hpp"

namespace swivel::calibration {
namespace {

TEST(CalibrationMotion, RobotTurnsAboutLockedWheelContact) {
  std::mt19937_64 rng(11);
  const auto truth = test::random_robot(4, rng);
  CalibrationMotionOptions opt;
  opt.start_pose = {1.2, -0.7, 2.9};  // crosses yaw = pi: the data wrap
  CalibrationInput input;
  std::string error;
  ASSERT_TRUE(generate_calibration_motion(truth, opt, rng, input, error)) << error;
  ASSERT_EQ(input.runs.size(), 8U);
  for (const LockedRun& run : input.runs) {
    const SwpcModuleParams& m = truth[run.locked_module];
    const double phi = run.locked_steer_meas_rad + m.steering_offset_rad;
    const double cx = m.x_m - m.caster_offset_m * std::cos(phi);
    const double cy = m.y_m - m.caster_offset_m * std::sin(phi);
    const RunSeries& d = run.data;
    const double w0x = d.x_m[0] + std::cos(d.yaw_rad[0]) * cx - std::sin(d.yaw_rad[0]) * cy;
    const double w0y = d.y_m[0] + std::sin(d.yaw_rad[0]) * cx + std::cos(d.yaw_rad[0]) * cy;
    for (std::size_t k = 0; k < d.t_s.size(); ++k) {
      const double wx = d.x_m[k] + std::cos(d.yaw_rad[k]) * cx - std::sin(d.yaw_rad[k]) * cy;
      const double wy = d.y_m[k] + std::sin(d.yaw_rad[k]) * cx + std::cos(d.yaw_rad[k]) * cy;
      ASSERT_NEAR(wx, w0x, 1e-12);
      ASSERT_NEAR(wy, w0y, 1e-12);
    }
  }
}

TEST(CalibrationMotion, FreeCastersSelfAlignAndRollTheArc) {
  std::mt19937_64 rng(12);
  const auto truth = test::random_robot(3, rng);
  CalibrationMotionOptions opt;
  CalibrationInput input;
  std::string error;
  ASSERT_TRUE(generate_calibration_motion(truth, opt, rng, input, error)) << error;
  for (const LockedRun& run : input.runs) {
    const SwpcModuleParams& lm = truth[run.locked_module];
    const double phi_l = run.locked_steer_meas_rad + lm.steering_offset_rad;
    const double px = lm.x_m - lm.caster_offset_m * std::cos(phi_l);
    const double py = lm.y_m - lm.caster_offset_m * std::sin(phi_l);
    for (std::size_t m = 0; m < truth.size(); ++m) {
      if (m == run.locked_module) continue;
      const double phi = run.data.steer_angle_rad[m].front() + truth[m].steering_offset_rad;
      const double ux = std::cos(phi);
      const double uy = std::sin(phi);
      const double cx = truth[m].x_m - truth[m].caster_offset_m * ux;
      const double cy = truth[m].y_m - truth[m].caster_offset_m * uy;
      // (axis -> contact) is perpendicular to (contact -> pivot)
      EXPECT_NEAR(-ux * (px - cx) - uy * (py - cy), 0.0, 1e-12);
      // Arc of the contact point equals the wheel's rolled distance: L theta = r psi.
      const double arm = std::hypot(px - cx, py - cy);
      const double psi = run.data.wheel_angle_rad[m].back() - run.data.wheel_angle_rad[m].front();
      const double theta = opt.yaw_rate_radps * run.data.t_s.back();
      EXPECT_NEAR(truth[m].wheel_radius_m * psi, arm * theta, 1e-12);
      EXPECT_GT(psi, 0.0);  // counter-clockwise rotation rolls the wheels forward
    }
  }
}

}  // namespace
}  // namespace swivel::calibration
