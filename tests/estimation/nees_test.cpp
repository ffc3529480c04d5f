// SPDX-License-Identifier: Apache-2.0
// Consistency of the published pose covariances against the simulator's ground truth: the
// normalised estimation error squared (NEES) e' P^-1 e, e = estimate - truth over (x, y,
// yaw), averaged over independent simulated runs, must lie within the chi-square interval
// of its degrees of freedom (Bar-Shalom, Li and Kirubarajan, "Estimation with Applications to
// Tracking and Navigation", 5.4.2). The truth is the simulator's own integration of the
// robot's true motion; the errors come from its sensor noise and its wheel slip and lateral
// scrub (first-order Gauss-Markov processes), none of which the estimators see.
//
// The scenario: the docent stands still for 2 s (the kalman filter's gyro bias settles), then
// drives the demo's rounded square (0.3 m/s, 0.5 m corner radius) for 60 s. Wheel slip of
// relative std s_w per wheel and lateral scrub of std s_c, both with correlation time tau,
// integrate over runs much longer than tau to a position variance growing per metre
// travelled: v s_w^2 tau along the motion (the two wheels' slips averaged) and
// 2 v s_c^2 tau across it. Those are the plugins' per-metre parameters here; the gyro noise
// is the robot model's. With s_c = s_w / sqrt(2) both are equal, so that the kalman filter's
// isotropic translation noise describes the same world.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "fault_rig.hpp"

namespace swivel::estimation {
namespace {

using faults::FaultRig;
using faults::RigOptions;

constexpr int kSeeds = 20;
constexpr double kSpeed = 0.3;
constexpr double kWheelSlipStd = 0.02;
constexpr double kScrubStd = kWheelSlipStd / std::numbers::sqrt2;
constexpr double kCorrelationS = 0.5;
constexpr double kStillS = 2.0;
constexpr double kDriveS = 60.0;
constexpr double kFirstCheckS = 10.0;  // of driving
constexpr double kCheckEveryS = 5.0;

// Per-metre position std of the scenario's slip and scrub (see the header).
double per_metre_noise() {
  return std::sqrt(kSpeed * kWheelSlipStd * kWheelSlipStd * kCorrelationS);
}

// Chi-square quantile by the Wilson-Hilferty transformation, accurate to about 1e-3
// relative for the 60 degrees of freedom used here.
double chi_square_quantile(double dof, double z) {
  const double a = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}

// Two-sided 99 % interval of the mean NEES over kSeeds runs of a 3-dimensional state.
struct Interval {
  double low;
  double high;
};
Interval nees_interval() {
  constexpr double kZ = 2.5758;  // 0.5 % in each tail
  const double dof = 3.0 * kSeeds;
  return {chi_square_quantile(dof, -kZ) / kSeeds, chi_square_quantile(dof, kZ) / kSeeds};
}

double nees(const StateSnapshot& s) {
  const Eigen::Vector3d e(
      s.estimate.pose.x_m - s.truth.x_m, s.estimate.pose.y_m - s.truth.y_m,
      std::remainder(s.estimate.pose.yaw_rad - s.truth.yaw_rad, 2.0 * std::numbers::pi));
  const Eigen::Matrix3d p =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(s.estimate.covariance.data());
  return e.dot(p.ldlt().solve(e));
}

std::string hardware(int seed) {
  return "{seed: " + std::to_string(seed) +
         ", sensor_noise: true, motion_capture: false, slip: {wheel_std: " +
         std::to_string(kWheelSlipStd) + ", lateral_scrub_std: " + std::to_string(kScrubStd) +
         ", correlation_time_s: " + std::to_string(kCorrelationS) + "}}";
}

std::string eg_noise() {
  const std::string k = std::to_string(per_metre_noise());
  return "along_track_noise_m_per_sqrt_m: " + k + ", cross_track_noise_m_per_sqrt_m: " + k +
         ", bias_random_walk_radps_per_sqrt_s: 0.0";
}

std::string raw_eg_params() { return "{" + eg_noise() + "}"; }
std::string lsm_params() { return "{" + eg_noise() + "}"; }
// The gyro bias is the nominal one in this world (zero); the filter learns that while the
// robot stands still.
std::string kalman_params() {
  return "{translation_noise_m_per_sqrt_m: " + std::to_string(per_metre_noise()) +
         ", yaw_noise_rad_per_sqrt_m: " +
         std::to_string(2.0 * kWheelSlipStd * std::sqrt(kSpeed * kCorrelationS) / 0.40) +
         ", rotation_noise_rad_per_sqrt_rad: 0.0, bias_random_walk_radps_per_sqrt_s: 0.0, "
         "use_pose_fixes: false}";
}

// The demo's rounded square: 1 m straight, a quarter turn of 0.5 m radius.
Twist2 square_command(double t_s) {
  constexpr double kStraightS = 1.0 / kSpeed;
  constexpr double kTurnS = 0.25 * std::numbers::pi * 0.5 / kSpeed;
  const double phase = std::fmod(t_s, kStraightS + kTurnS);
  return phase < kStraightS ? Twist2{kSpeed, 0.0, 0.0} : Twist2{kSpeed, 0.0, kSpeed / 0.5};
}

/// One swap during a run: at `at_s` of driving, to `plugin` with `params`.
struct Swap {
  double at_s;
  std::string plugin;
  std::string params;
};

/// NEES per check time (rows) and seed (columns).
using NeesTable = std::vector<std::vector<double>>;

NeesTable run_seeds(const std::string& plugin, const std::string& params,
                    const std::vector<Swap>& swaps = {}) {
  const int checks = static_cast<int>((kDriveS - kFirstCheckS) / kCheckEveryS) + 1;
  NeesTable table(static_cast<std::size_t>(checks));
  for (int seed = 1; seed <= kSeeds; ++seed) {
    RigOptions o;
    o.hardware_params = hardware(seed);
    o.localization = plugin;
    o.localization_params = params;
    FaultRig rig(o);
    rig.drive(0.0, 0.0, 0.0, static_cast<int>(kStillS / FaultRig::kDtS));
    std::vector<PluginInstance<Localization>> incoming;
    std::size_t next_swap = 0;
    const int cycles = static_cast<int>(kDriveS / FaultRig::kDtS);
    for (int i = 1; i <= cycles; ++i) {
      const double t = i * FaultRig::kDtS;
      if (next_swap < swaps.size() && t >= swaps[next_swap].at_s) {
        const Swap& swap = swaps[next_swap++];
        auto next = rig.make_localization(swap.plugin, swap.params);
        next->reset(rig.state().estimate);  // off the loop, as the daemon does
        const std::array<double, 9> before = rig.state().estimate.covariance;
        EXPECT_TRUE(rig.loop->request_localization_swap(next.get(), swap.plugin.c_str()));
        const Twist2 c = square_command(t);
        rig.drive(c.vx_mps, c.vy_mps, c.wz_radps, 1);
        (void)rig.loop->take_retired_localization();
        incoming.push_back(std::move(next));
        // The covariance went over with the pose: one cycle's growth (an incoming kalman
        // filter's own bias uncertainty adds its share to the yaw), no reset and no default.
        const StateSnapshot after = rig.state();
        EXPECT_STREQ(after.localization_plugin.data(), swap.plugin.c_str());
        for (const std::size_t k : {0, 4, 8}) {
          EXPECT_NEAR(after.estimate.covariance[k], before[k], 1e-2 * before[k] + 1e-9)
              << "seed " << seed << ", swap to " << swap.plugin << ", entry " << k;
        }
        continue;
      }
      const Twist2 c = square_command(t);
      rig.drive(c.vx_mps, c.vy_mps, c.wz_radps, 1);
      const double since_first = t - kFirstCheckS;
      if (since_first >= -1e-9 && std::abs(std::remainder(since_first, kCheckEveryS)) < 1e-9) {
        const StateSnapshot s = rig.state();
        EXPECT_EQ(s.fault, FaultCode::kNone);
        EXPECT_TRUE(s.has_truth && s.estimate.has_covariance);
        table[static_cast<std::size_t>(std::lround(since_first / kCheckEveryS))].push_back(nees(s));
      }
    }
  }
  return table;
}

// Prints the mean NEES at every check time and expects it inside the interval.
void expect_consistent(const char* what, const NeesTable& table) {
  const Interval bounds = nees_interval();
  std::printf("%s: mean NEES over %d seeds, 99 %% interval [%.2f, %.2f]\n  t(s):", what, kSeeds,
              bounds.low, bounds.high);
  for (std::size_t k = 0; k < table.size(); ++k) {
    std::printf(" %5.0f", kFirstCheckS + kCheckEveryS * static_cast<double>(k));
  }
  std::printf("\n  NEES:");
  double overall = 0.0;
  for (const auto& row : table) {
    double mean = 0.0;
    for (const double v : row) mean += v / static_cast<double>(row.size());
    overall += mean / static_cast<double>(table.size());
    std::printf(" %5.2f", mean);
  }
  std::printf("   (mean %.2f)\n", overall);
  for (std::size_t k = 0; k < table.size(); ++k) {
    ASSERT_EQ(table[k].size(), static_cast<std::size_t>(kSeeds));
    double mean = 0.0;
    for (const double v : table[k]) mean += v / kSeeds;
    EXPECT_GT(mean, bounds.low) << what << " at check " << k;
    EXPECT_LT(mean, bounds.high) << what << " at check " << k;
  }
}

TEST(Nees, IntervalIsTheChiSquareOne) {
  // Table values for 60 degrees of freedom: 0.5 % 35.534, 99.5 % 91.952.
  EXPECT_NEAR(chi_square_quantile(60.0, -2.5758), 35.534, 0.05);
  EXPECT_NEAR(chi_square_quantile(60.0, 2.5758), 91.952, 0.05);
}

TEST(Nees, RawEgCovarianceIsConsistent) {
  expect_consistent("raw_eg", run_seeds("raw_eg", raw_eg_params()));
}

TEST(Nees, LsmCovarianceIsConsistent) { expect_consistent("lsm", run_seeds("lsm", lsm_params())); }

TEST(Nees, LsmHeadingAlignedCovarianceIsConsistent) {
  // On 1 m sides there is little lateral drift for its projection to remove; on long straight
  // runs its covariance is an upper bound (lsm_localization.hpp).
  expect_consistent("lsm heading_aligned",
                    run_seeds("lsm", "{mode: heading_aligned, " + eg_noise() + "}"));
}

TEST(Nees, AMisstatedNoiseModelIsCaught) {
  // Twice the world's per-metre noise: the covariance is four times too large where the
  // translation dominates, and the mean NEES falls below the interval.
  const std::string k = std::to_string(2.0 * per_metre_noise());
  const NeesTable table = run_seeds("raw_eg", "{along_track_noise_m_per_sqrt_m: " + k +
                                                  ", cross_track_noise_m_per_sqrt_m: " + k +
                                                  ", bias_random_walk_radps_per_sqrt_s: 0.0}");
  const Interval bounds = nees_interval();
  for (std::size_t c = 0; c < table.size(); ++c) {
    double mean = 0.0;
    for (const double v : table[c]) mean += v / kSeeds;
    EXPECT_LT(mean, bounds.low) << "check " << c;
  }
}

TEST(Nees, KalmanCovarianceIsConsistent) {
  expect_consistent("kalman", run_seeds("kalman", kalman_params()));
}

TEST(Nees, CovarianceSurvivesHotSwaps) {
  expect_consistent("raw_eg -> kalman (22 s) -> lsm (37 s) -> raw_eg (52 s)",
                    run_seeds("raw_eg", raw_eg_params(),
                              {{22.0, "kalman", kalman_params()},
                               {37.0, "lsm", lsm_params()},
                               {52.0, "raw_eg", raw_eg_params()}}));
}

}  // namespace
}  // namespace swivel::estimation
