// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/pose_ekf.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

namespace swivel::localization {
namespace {

constexpr double kDt = 0.001;
using Matrix3 = PoseEkf::Matrix3;

PoseEkf make_filter(const EkfNoise& noise, double bias_sigma) {
  PoseEkf ekf;
  ekf.set_noise(noise);
  ekf.reset(Pose2{}, Matrix3::Zero(), 0.0, bias_sigma * bias_sigma);
  return ekf;
}

TEST(PoseEkf, GyroBiasConvergesOnStraightLine) {
  // Exact odometry of a straight run at 0.3 m/s; the gyro reads bias + white noise.
  const double bias = 0.01;
  const double v = 0.3;
  EkfNoise noise;
  PoseEkf ekf = make_filter(noise, 0.02);
  std::mt19937_64 rng(42);
  std::normal_distribution<double> gyro_noise(0.0, noise.gyro_noise_radps);
  const int steps = 60000;  // 60 s
  for (int i = 0; i < steps; ++i) {
    ASSERT_EQ(ekf.step(Pose2{v * kDt, 0.0, 0.0}, kDt, bias + gyro_noise(rng), true),
              EkfResult::kOk);
  }
  const double bias_sd = std::sqrt(ekf.covariance()(3, 3));
  // Within 10 % of the bias, and within the filter's own 3 sigma.
  EXPECT_NEAR(ekf.bias_radps(), bias, 1e-3);
  EXPECT_LT(std::abs(ekf.bias_radps() - bias), 3.0 * bias_sd);
  // Uncompensated, the heading would have drifted bias * t = 0.6 rad.
  EXPECT_LT(std::abs(ekf.pose().yaw_rad), 5e-3);
  EXPECT_NEAR(ekf.pose().x_m, v * steps * kDt, 1e-3);
}

TEST(PoseEkf, GyroBiasConvergesFastWhenStill) {
  const double bias = -0.007;
  EkfNoise noise;
  PoseEkf ekf = make_filter(noise, 0.02);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gyro_noise(0.0, noise.gyro_noise_radps);
  for (int i = 0; i < 2000; ++i) {
    ASSERT_EQ(ekf.step(Pose2{}, kDt, bias + gyro_noise(rng), true), EkfResult::kOk);
  }
  // Still: the encoders say "no rotation" exactly, so each reading measures the bias with
  // the gyro's own noise: sd 0.002 / sqrt(2000) = 4.5e-5.
  EXPECT_NEAR(ekf.bias_radps(), bias, 2e-4);
  EXPECT_EQ(ekf.pose().yaw_rad, 0.0);
}

TEST(PoseEkf, CovarianceStaysSymmetricPsdOverLongRandomRun) {
  EkfNoise noise;
  PoseEkf ekf = make_filter(noise, 0.02);
  std::mt19937_64 rng(1234);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::bernoulli_distribution gyro_ok(0.9);
  std::bernoulli_distribution fix(0.01);
  for (int i = 0; i < 200000; ++i) {
    const double v = 0.5 * uni(rng);
    const double vy = 0.1 * uni(rng);
    const double w = 1.5 * uni(rng);
    const Pose2 delta{v * kDt, vy * kDt, w * kDt};
    ASSERT_EQ(ekf.step(delta, kDt, w + 0.01 + 0.002 * gauss(rng), gyro_ok(rng)), EkfResult::kOk)
        << "step " << i;
    if (fix(rng)) {
      const Pose2 p = ekf.pose();
      ASSERT_EQ(ekf.update_pose_fix(Pose2{p.x_m + 0.01 * gauss(rng), p.y_m + 0.01 * gauss(rng),
                                          p.yaw_rad + 0.01 * gauss(rng)}),
                EkfResult::kOk)
          << "fix " << i;
    }
    if (i % 1000 == 0) {
      const PoseEkf::Matrix4& p = ekf.covariance();
      ASSERT_EQ((p - p.transpose()).cwiseAbs().maxCoeff(), 0.0);
      const Eigen::SelfAdjointEigenSolver<PoseEkf::Matrix4> eig(p, Eigen::EigenvaluesOnly);
      ASSERT_GE(eig.eigenvalues().minCoeff(), -1e-12 * p.diagonal().maxCoeff()) << "step " << i;
    }
  }
}

TEST(PoseEkf, PoseFixPullsTowardTruthAndShrinksCovariance) {
  EkfNoise noise;
  noise.fix_position_noise_m = 0.01;
  noise.fix_yaw_noise_rad = 0.02;
  PoseEkf ekf;
  ekf.set_noise(noise);
  Matrix3 cov = Matrix3::Zero();
  cov.diagonal() << 0.04, 0.04, 0.01;  // 0.2 m, 0.2 m, 0.1 rad
  ekf.reset(Pose2{1.0, -0.5, 0.1}, cov, 0.0, 1e-4);
  ASSERT_EQ(ekf.update_pose_fix(Pose2{0.0, 0.0, 0.0}), EkfResult::kOk);
  // Scalar Kalman per axis (uncorrelated prior): x + P/(P+R) (z - x).
  EXPECT_NEAR(ekf.pose().x_m, 1.0 * (1.0 - 0.04 / (0.04 + 1e-4)), 1e-12);
  EXPECT_NEAR(ekf.pose().y_m, -0.5 * (1.0 - 0.04 / (0.04 + 1e-4)), 1e-12);
  EXPECT_NEAR(ekf.pose().yaw_rad, 0.1 * (1.0 - 0.01 / (0.01 + 4e-4)), 1e-12);
  EXPECT_NEAR(ekf.covariance()(0, 0), 0.04 * 1e-4 / (0.04 + 1e-4), 1e-15);
  EXPECT_LT(ekf.covariance().trace(), 0.01 * cov.trace());
}

TEST(PoseEkf, YawInnovationIsWrapped) {
  PoseEkf ekf;
  Matrix3 cov = Matrix3::Identity();
  ekf.reset(Pose2{0.0, 0.0, 3.1}, cov, 0.0, 1e-4);
  ASSERT_EQ(ekf.update_pose_fix(Pose2{0.0, 0.0, -3.1}), EkfResult::kOk);
  // Across +-pi the fix is 0.083 rad away, not 6.2: the estimate stays near pi.
  EXPECT_GT(std::abs(ekf.pose().yaw_rad), 3.1);
}

TEST(PoseEkf, RejectsNonPsdAndNonFiniteInputs) {
  PoseEkf ekf;
  ekf.reset(Pose2{}, Matrix3::Identity() * 0.01, 0.0, 1e-4);
  Matrix3 bad = Matrix3::Identity();
  bad(0, 1) = bad(1, 0) = 2.0;  // eigenvalues 3 and -1
  EXPECT_EQ(ekf.set_pose(Pose2{1.0, 1.0, 0.0}, &bad), EkfResult::kNotPsd);
  EXPECT_EQ(ekf.pose().x_m, 0.0);  // unchanged
  EXPECT_EQ(ekf.step(Pose2{std::nan(""), 0.0, 0.0}, kDt, 0.0, true), EkfResult::kNonFinite);
  EXPECT_EQ(ekf.step(Pose2{}, 0.0, 0.0, true), EkfResult::kNonFinite);
  EXPECT_FALSE(is_psd(PoseEkf::Matrix4::Identity() * -1.0));
  EXPECT_TRUE(is_psd(PoseEkf::Matrix4::Zero()));
}

}  // namespace
}  // namespace swivel::localization
