// SPDX-License-Identifier: Apache-2.0
// EgCovariance against closed forms of its noise model.

#include "swivel/localization/eg_covariance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace swivel::localization {
namespace {

constexpr double kDt = 0.001;

EgNoise only(double along, double cross) {
  EgNoise n;
  n.along_track_m_per_sqrt_m = along;
  n.cross_track_m_per_sqrt_m = cross;
  n.rotation_rad_per_sqrt_rad = 0.0;
  n.yaw_rad_per_sqrt_m = 0.0;
  n.gyro_noise_radps = 0.0;
  n.gyro_bias_sigma_radps = 0.0;
  n.bias_walk_radps_per_sqrt_s = 0.0;
  return n;
}

TEST(EgCovariance, TranslationGrowsPerMetreAlongAndAcrossTheMotion) {
  for (const double heading : {0.0, std::numbers::pi / 2}) {
    EgCovariance cov;
    cov.set_noise(only(0.02, 0.005));
    cov.reset(Eigen::Matrix3d::Zero());
    for (int k = 0; k < 1000; ++k) cov.step(Pose2{0.002, 0.0, 0.0}, kDt, heading, false);
    const double along = 0.02 * 0.02 * 2.0;  // 2 m travelled
    const double cross = 0.005 * 0.005 * 2.0;
    const auto& p = cov.covariance();
    EXPECT_NEAR(p(0, 0), heading == 0.0 ? along : cross, 1e-12) << heading;
    EXPECT_NEAR(p(1, 1), heading == 0.0 ? cross : along, 1e-12) << heading;
    EXPECT_NEAR(p(0, 1), 0.0, 1e-12);
    EXPECT_EQ(p(2, 2), 0.0);
  }
}

TEST(EgCovariance, SidewaysStepIsAlongItsOwnDirection) {
  // A holonomic step to the left of a robot heading along x moves along y: its along-track
  // noise is in y.
  EgCovariance cov;
  cov.set_noise(only(0.02, 0.0));
  cov.reset(Eigen::Matrix3d::Zero());
  cov.step(Pose2{0.0, 0.5, 0.0}, kDt, 0.0, false);
  EXPECT_NEAR(cov.covariance()(0, 0), 0.0, 1e-15);
  EXPECT_NEAR(cov.covariance()(1, 1), 0.02 * 0.02 * 0.5, 1e-15);
}

TEST(EgCovariance, HeadingErrorTurnsIntoLateralError) {
  // Yaw variance s2 at the start, a straight run of L metres with no other noise: the
  // lateral error is L times the heading error.
  EgCovariance cov;
  cov.set_noise(only(0.0, 0.0));
  Eigen::Matrix3d start = Eigen::Matrix3d::Zero();
  start(2, 2) = 1e-4;
  cov.reset(start);
  for (int k = 0; k < 500; ++k) cov.step(Pose2{0.004, 0.0, 0.0}, kDt, 0.0, false);
  const double length = 2.0;
  EXPECT_NEAR(cov.covariance()(1, 1), length * length * 1e-4, 1e-12);
  EXPECT_NEAR(cov.covariance()(1, 2), length * 1e-4, 1e-12);
  EXPECT_NEAR(cov.covariance()(0, 0), 0.0, 1e-15);
}

TEST(EgCovariance, GyroNoiseAndResidualBiasGrowTheHeading) {
  EgNoise n = only(0.0, 0.0);
  n.gyro_noise_radps = 0.002;
  n.gyro_bias_sigma_radps = 0.001;
  EgCovariance cov;
  cov.set_noise(n);
  cov.reset(Eigen::Matrix3d::Zero());
  const int steps = 10000;  // 10 s still
  for (int k = 0; k < steps; ++k) cov.step(Pose2{}, kDt, 0.0, true);
  const double t = steps * kDt;
  // White noise: N (sigma dt)^2; the bias: (sigma_b t)^2, correlated with the bias by sigma_b^2 t.
  EXPECT_NEAR(cov.covariance()(2, 2), steps * std::pow(0.002 * kDt, 2) + std::pow(0.001 * t, 2),
              1e-15);
  EXPECT_NEAR(cov.covariance()(2, 3), 0.001 * 0.001 * t, 1e-15);
  EXPECT_NEAR(cov.covariance()(3, 3), 0.001 * 0.001, 1e-18);
}

TEST(EgCovariance, EncoderHeadingGrowsPerRadianAndPerMetre) {
  EgNoise n = only(0.0, 0.0);
  n.rotation_rad_per_sqrt_rad = 0.05;
  n.yaw_rad_per_sqrt_m = 0.01;
  n.gyro_bias_sigma_radps = 0.1;  // not used by the encoder heading
  EgCovariance cov;
  cov.set_noise(n);
  cov.reset(Eigen::Matrix3d::Zero());
  for (int k = 0; k < 1000; ++k) cov.step(Pose2{0.0, 0.0, -0.001}, kDt, 0.0, false);  // 1 rad
  for (int k = 0; k < 1000; ++k) cov.step(Pose2{0.003, 0.0, 0.0}, kDt, 0.0, false);   // 3 m
  EXPECT_NEAR(cov.covariance()(2, 2), 0.05 * 0.05 * 1.0 + 0.01 * 0.01 * 3.0, 1e-12);
  EXPECT_EQ(cov.covariance()(2, 3), 0.0);
}

TEST(EgCovariance, SetPoseCovarianceTakesOnlyACovariance) {
  EgCovariance cov;
  EgNoise n;
  n.gyro_bias_sigma_radps = 0.01;
  cov.set_noise(n);
  cov.reset(Eigen::Matrix3d::Zero());
  for (int k = 0; k < 100; ++k) cov.step(Pose2{0.001, 0.0, 0.0}, kDt, 0.0, true);
  Eigen::Matrix3d handed = Eigen::Matrix3d::Identity() * 0.04;
  handed(0, 1) = handed(1, 0) = 0.01;
  ASSERT_TRUE(cov.set_pose_covariance(handed));
  EXPECT_TRUE((cov.covariance().topLeftCorner<3, 3>().isApprox(handed)));
  EXPECT_EQ(cov.covariance()(2, 3), 0.0);            // the correlation with the bias is dropped
  EXPECT_NEAR(cov.covariance()(3, 3), 1e-4, 1e-18);  // the bias variance kept

  Eigen::Matrix3d not_psd = Eigen::Matrix3d::Identity();
  not_psd(0, 0) = -1.0;
  EXPECT_FALSE(cov.set_pose_covariance(not_psd));
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(cov.set_pose_covariance(nan));
  EXPECT_TRUE((cov.covariance().topLeftCorner<3, 3>().isApprox(handed)));  // unchanged
  EXPECT_TRUE(is_covariance(Eigen::Matrix3d::Zero()));
}

}  // namespace
}  // namespace swivel::localization
