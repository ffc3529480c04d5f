// SPDX-License-Identifier: Apache-2.0
// A gap the misfit tests detect, put down to the candidate that takes it away although that
// candidate's own F test, resting on the few windows where the effect acts, stays below the
// significance needed to name an effect unasked (a run of the second robot generator).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "second_runs.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/second/validation_set.hpp"

namespace swivel::model_gap {
namespace {

// Whether the question named `effect` and nothing else.
::testing::AssertionResult named_alone(const QuestionResult& q, const std::string& effect) {
  if (q.verdict != Verdict::kNamed || q.named.size() != 1 || q.named[0].name != effect)
    return ::testing::AssertionFailure() << "not " << effect << " alone: " << q.summary;
  return ::testing::AssertionSuccess();
}

// trike3 whose casters steer 0.093 s late where its model states no lag (the fifth validation
// set's 15th case with one hidden effect, development data now). The lag shows only while casters
// swing: its candidate removes 92 % of the command question's whitened residual (BIC -1027), but
// its F test has the few degrees of freedom of those windows and reaches 4.96 sigma. Without it,
// the residual jumps by up to 11 sigma where casters swing.
TEST(GapAttribution, ASteeringLagTheMisfitTestsDetectIsNamed) {
  const HiddenEffectRun lag = hidden_effect_run(second::kFifthValidationSeeds, 14, "steering_lag");
  const GapResult gap = analyse_gap(lag.run.model, lag.run.run);
  const QuestionResult& q = gap.command;
  ASSERT_TRUE(named_alone(q, "steering_lag"));
  EXPECT_LT(q.named[0].z, QuestionOptions{}.min_z_name) << "named by attribution, not alone";
  ASSERT_EQ(q.attributed_gap.size(), 1U);
  EXPECT_GE(q.attributed_gap[0].z, QuestionOptions{}.min_z_misfit);
  EXPECT_NE(q.summary.find("is gone with it"), std::string::npos) << q.summary;
  const double value = q.named[0].values.at(0);
  const double sigma = q.named[0].sigmas.at(0);
  EXPECT_LT(std::abs(value - lag.truth), 4.0 * sigma)
      << "fitted " << value << " +- " << sigma << ", true " << lag.truth;
  EXPECT_EQ(gap.sensor.verdict, Verdict::kNoSignificantGap) << gap.sensor.summary;
}

// cart4 at 21 Hz whose true acceleration limits (0.056 m/s^2, 0.107 rad/s^2) its model lacks
// (the fifth validation set's 34th case with one hidden effect, development data now). The limits
// are fitted within a sigma of the truth, but the generator's wheels reach them through a tyre
// force, not as the replay's clipped command: two windows of wheel 1, where the limit changes the
// prediction most, keep jumps of 12 noise sigmas of the much larger change it brings there.
TEST(GapAttribution, JumpsLeftWhereANamedLimitActsAreItsApproximateForm) {
  const HiddenEffectRun limit = hidden_effect_run(second::kFifthValidationSeeds, 33, "accel_limit");
  const GapResult gap = analyse_gap(limit.run.model, limit.run.run);
  const QuestionResult& q = gap.command;
  ASSERT_TRUE(named_alone(q, "accel_limit"));
  EXPECT_NE(q.summary.find("(its form is approximate)"), std::string::npos) << q.summary;
  const QuestionOptions options;
  bool remnant_counts_otherwise = false;
  for (const MisfitTest& m : q.misfits) {
    remnant_counts_otherwise |=
        m.remnant && m.z >= options.min_z_misfit && m.size >= options.min_misfit_size;
  }
  EXPECT_TRUE(remnant_counts_otherwise) << "without the remnant rule the verdict is unexplained";
  // The truth's keys ("linear_mps2") and the model's ("linear_acceleration_mps2") share the
  // axis, their first word.
  const auto axis = [](const std::string& key) { return key.substr(0, key.find('_')); };
  for (const auto& param : limit.spec.expected[0].params) {
    const std::string& key = param.first;
    const double truth = param.second;
    const auto k = static_cast<std::size_t>(
        std::ranges::find_if(q.named[0].keys,
                             [&](const std::string& named) { return axis(named) == axis(key); }) -
        q.named[0].keys.begin());
    ASSERT_LT(k, q.named[0].keys.size()) << key;
    EXPECT_LT(std::abs(q.named[0].values[k] - truth), 3.0 * q.named[0].sigmas[k]) << key;
  }
}

}  // namespace
}  // namespace swivel::model_gap
