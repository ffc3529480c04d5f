// SPDX-License-Identifier: Apache-2.0
// The representative subset of the independent battery (tests/independent_robot): runs the
// workflow did not make, from a robot it does not simulate, judged by the same rules as
// `swivel-bench-model-gap --battery` (battery_scoring.hpp). The whole battery is the
// benchmark's; its figures are quoted in tools/lab/GAP.md.

#include <gtest/gtest.h>

#include <cctype>
#include <ostream>
#include <string>

#include "battery_scoring.hpp"

namespace swivel::independent {
// Test names and failures show the case by its id (GoogleTest finds the printer by this name).
// NOLINTNEXTLINE(readability-identifier-naming)
void PrintTo(const BatteryCase& c, std::ostream* os) { *os << c.id; }
}  // namespace swivel::independent

namespace swivel::model_gap {
namespace {

class BatterySubsetTest : public ::testing::TestWithParam<independent::BatteryCase> {};

TEST_P(BatterySubsetTest, AnswersAsTheBatteryRequires) {
  const independent::BatteryCase& c = GetParam();
  const battery::CaseOutcome o = battery::run_case(c);
  EXPECT_TRUE(o.correct) << o.problem << "\n  sensor to pose: " << o.summary[0]
                         << "\n  command to motion: " << o.summary[1];
  if (c.kind == independent::CaseKind::kSingle || c.kind == independent::CaseKind::kPair) {
    std::string values;
    for (const auto& p : o.params) {
      values += "\n  " + p.effect + "." + p.key + ": truth " + std::to_string(p.truth) +
                ", fitted " + std::to_string(p.value) + " +- " + std::to_string(p.sigma);
    }
    EXPECT_TRUE(o.values_within_3_sigma) << values;
  }
  if (c.kind == independent::CaseKind::kOutside) {
    // Outside the library: said so, not only left unnamed.
    EXPECT_TRUE(o.verdict[0] == Verdict::kUnexplained || o.verdict[1] == Verdict::kUnexplained)
        << o.summary[0] << "\n"
        << o.summary[1];
  }
}

std::string case_name(const ::testing::TestParamInfo<independent::BatteryCase>& info) {
  std::string name;
  for (char ch : info.param.id)
    name += (std::isalnum(static_cast<unsigned char>(ch)) != 0) ? ch : '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(Subset, BatterySubsetTest,
                         ::testing::ValuesIn(independent::battery_subset()), case_name);

}  // namespace
}  // namespace swivel::model_gap
