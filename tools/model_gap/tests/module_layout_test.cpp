// SPDX-License-Identifier: Apache-2.0
// module_layout end to end: a four-caster robot whose modules sit 2 % wider apart than its
// model says is named by the sensor question, with the true layout inside the fit's 3 sigma
// over the combinations the run fixes, and the gap it leaves shrinks; a clean run does not
// name it.
//
// What a run fixes of a layout: the dead reckoning solves every module's steering-axis
// velocity v + w J p_i for the body twist, and a layout centred on the robot's origin (the sum
// of the p_i zero) changes only the turn rate, through sum p_i . dp_i. So a run tells the
// layout's spread about the centre, sum x_i^2 (longitudinal - 1) + sum y_i^2 (lateral - 1),
// and not how it is shared between the two axes (GAP.md, section 4).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

#include "gap_fixtures.hpp"
#include "swivel/model_gap/fit.hpp"
#include "swivel/model_gap/fold_effects.hpp"
#include "swivel/model_gap/run_log_adapter.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {
namespace {

constexpr double kLateralScale = 1.02;

GapResult analyse_layout(double lateral_scale, std::uint64_t seed) {
  const RobotModel nominal = testing::robot("swpc4");
  RobotModel truth = nominal;
  if (lateral_scale != 1.0) truth.effects["module_layout"]["lateral_scale"] = lateral_scale;
  return analyse_gap(nominal, to_run_data(testing::simulate_run(nominal, truth, 60.0, seed)));
}

const ChannelGap* channel(const QuestionResult& q, const std::string& name) {
  const auto it = std::ranges::find_if(
      q.channels, [&name](const ChannelGap& c) { return c.info.name == name; });
  return it == q.channels.end() ? nullptr : &*it;
}

const PoseGap* pose_gap(const GapResult& r, Question question) {
  const auto it = std::ranges::find_if(
      r.pose_gaps, [question](const PoseGap& g) { return g.question == question; });
  return it == r.pose_gaps.end() ? nullptr : &*it;
}

// The layout's spread about the centre relative to the nominal one's, minus 1, as weights on
// (lateral_scale - 1, longitudinal_scale - 1): what a run fixes of the two scales.
std::vector<double> spread_weights(const RobotModel& model) {
  double xx = 0.0;
  double yy = 0.0;
  for (const SwpcModuleParams& m : model.modules) {
    xx += m.x_m * m.x_m;
    yy += m.y_m * m.y_m;
  }
  return {yy / (xx + yy), xx / (xx + yy)};
}

TEST(ModuleLayout, WiderModulesAreNamedWithinTheirSigmasAndTheGapShrinks) {
  const GapResult r = analyse_layout(kLateralScale, 7);
  ASSERT_EQ(r.sensor.verdict, Verdict::kNamed) << r.sensor.summary;
  ASSERT_EQ(r.sensor.named.size(), 1U) << r.sensor.summary;
  EXPECT_EQ(r.command.verdict, Verdict::kNoSignificantGap) << r.command.summary;
  const FittedEffect& e = r.sensor.named[0];
  ASSERT_EQ(e.name, "module_layout") << r.sensor.summary;
  ASSERT_EQ(e.keys, (std::vector<std::string>{"lateral_scale", "longitudinal_scale"}));
  ASSERT_EQ(e.fit_values.size(), 2U);
  ASSERT_EQ(e.fit_covariance.size(), 4U);

  // The truth within 3 sigma, jointly over the combinations the run fixes (as the battery
  // judges every effect): here one, the spread; the share between the axes stays at the
  // model's.
  const std::vector<double> difference = {e.fit_values[0] - kLateralScale, e.fit_values[1] - 1.0};
  std::size_t rank = 0;
  const double chi2 = mahalanobis_squared(difference, e.fit_covariance, rank);
  EXPECT_EQ(rank, 1U);
  EXPECT_EQ(e.observable_combinations, 1U);
  EXPECT_LE(chi_square_z(chi2, static_cast<double>(rank)), 3.0)
      << "lateral " << e.values[0] << " +- " << e.partial_sigmas[0] << ", longitudinal "
      << e.values[1] << " +- " << e.partial_sigmas[1];
  // The spread itself, with its sigma from the fit's covariance.
  const RobotModel& nominal = r.nominal;
  const std::vector<double> w = spread_weights(nominal);
  const double truth_spread = w[0] * (kLateralScale - 1.0);
  const double spread = w[0] * (e.values[0] - 1.0) + w[1] * (e.values[1] - 1.0);
  const std::vector<double>& c = e.fit_covariance;
  const double spread_sigma =
      std::sqrt(w[0] * w[0] * c[0] + 2.0 * w[0] * w[1] * c[1] + w[1] * w[1] * c[3]);
  std::cout << "module_layout: lateral_scale " << e.values[0] << " +- " << e.partial_sigmas[0]
            << ", longitudinal_scale " << e.values[1] << " +- " << e.partial_sigmas[1]
            << " (of what the run fixes); spread " << spread << " +- " << spread_sigma << ", truth "
            << truth_spread << "\n";
  EXPECT_LE(std::abs(spread - truth_spread), 3.0 * spread_sigma);

  // The gap shrinks: the encoders' heading, where a layout shows, and the command replay's
  // path, which moves the replayed robot with the model's layout.
  const ChannelGap* heading = channel(r.sensor, "dead_reckoning.dyaw_encoders_rad");
  ASSERT_NE(heading, nullptr);
  EXPECT_LT(heading->whitened_rms_after, 0.5 * heading->whitened_rms_before);
  EXPECT_LT(heading->whitened_rms_after, 1.5);
  const PoseGap* replay = pose_gap(r, Question::kCommandToMotion);
  ASSERT_NE(replay, nullptr);
  EXPECT_LT(replay->final_heading_rad_after, 0.5 * replay->final_heading_rad_before);
  EXPECT_LT(replay->rms_position_m_after, replay->rms_position_m_before);

  // What the daemon loads: the module positions moved, the same world as with the effect.
  const FoldResult folded = fold_effects(r.augmented);
  EXPECT_TRUE(folded.model.effects.empty());
  const sim::PlantParams with_effect = sim::resolve_plant(r.augmented);
  const sim::PlantParams in_model = sim::resolve_plant(folded.model);
  for (std::size_t i = 0; i < nominal.modules.size(); ++i) {
    EXPECT_EQ(in_model.modules[i].x_m, with_effect.modules[i].x_m) << "module " << i;
    EXPECT_EQ(in_model.modules[i].y_m, with_effect.modules[i].y_m) << "module " << i;
  }
}

TEST(ModuleLayout, ACleanRunDoesNotNameIt) {
  for (const std::uint64_t seed : {21U, 33U}) {
    const GapResult r = analyse_layout(1.0, seed);
    EXPECT_EQ(r.sensor.verdict, Verdict::kNoSignificantGap) << seed << ": " << r.sensor.summary;
    EXPECT_TRUE(r.named().empty()) << seed << ": " << r.summary;
    const auto layout = std::ranges::find_if(r.sensor.candidates, [](const CandidateScore& c) {
      return c.effects == std::vector<std::string>{"module_layout"};
    });
    ASSERT_NE(layout, r.sensor.candidates.end()) << seed << ": not a candidate";
    ASSERT_FALSE(layout->z.empty());
    EXPECT_LT(layout->z[0], 5.0) << seed;
  }
}

}  // namespace
}  // namespace swivel::model_gap
