// SPDX-License-Identifier: Apache-2.0
// The battery's coverage: every library effect at two sizes on each robot it applies to,
// clean runs, pairs and effects outside the library, and every case producing valid files.

#include "swivel/independent/battery.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "swivel/independent/generator.hpp"
#include "swivel/independent/outside_effects.hpp"
#include "swivel/independent/run_files.hpp"
#include "swivel/independent/tour.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_log.hpp"

namespace swivel::independent {
namespace {

const std::map<std::string, std::vector<std::string>>& library_effects_by_robot() {
  static const std::map<std::string, std::vector<std::string>> effects{
      {"docent",
       {"gyro_bias", "gyro_scale", "wheel_radius", "track_width", "sensor_latency", "actuator_lag",
        "accel_limit", "slip"}},
      {"swpc4",
       {"gyro_bias", "gyro_scale", "wheel_radius", "caster_offset", "steering_offset",
        "sensor_latency", "actuator_lag", "steering_lag", "steering_rate_limit", "accel_limit",
        "slip"}}};
  return effects;
}

// How far an expected effect is from "nothing wrong": the largest relative departure of its
// parameters (limits: how much lower than the nominal, or absent, they are).
double size_of(const ExpectedEffect& e) {
  const std::map<std::string, double> nominal_limits{
      {"linear_mps2", 0.6}, {"angular_radps2", 2.0}, {"radps", 6.0}};
  double size = 0.0;
  for (const ExpectedParam& p : e.params) {
    double departure = 0.0;
    if (e.effect == "accel_limit" || e.effect == "steering_rate_limit") {
      departure = 1.0 / p.value;  // a lower limit acts more often
    } else if (p.key.find("scale") != std::string::npos) {
      departure = std::abs(p.value - 1.0);
    } else {
      departure = std::abs(p.value);
    }
    size = std::max(size, departure);
  }
  return size;
}

TEST(Battery, HasAtLeastFortyCasesWithUniqueIdsThatFindCaseReturns) {
  const std::vector<BatteryCase>& cases = battery();
  EXPECT_GE(cases.size(), 40U);
  std::set<std::string> ids;
  for (const BatteryCase& c : cases) {
    EXPECT_TRUE(ids.insert(c.id).second) << "duplicate id " << c.id;
    EXPECT_EQ(find_case(c.id), &c);
    EXPECT_EQ(c.id.substr(0, c.id.find('/')), c.robot);
    EXPECT_EQ(robot_name(c.spec.robot), c.robot);
    EXPECT_FALSE(c.description.empty());
    EXPECT_EQ(c.spec.duration_s, 120.0) << c.id;
  }
  EXPECT_EQ(find_case("docent/no_such_case"), nullptr);
}

TEST(Battery, EveryLibraryEffectAppearsAloneAtTwoSizesOnEachRobot) {
  for (const auto& [robot, effects] : library_effects_by_robot()) {
    for (const std::string& effect : effects) {
      std::string prefix = robot;
      prefix.append("/").append(effect);
      const BatteryCase* small = find_case(prefix + "/small");
      const BatteryCase* large = find_case(prefix + "/large");
      ASSERT_NE(small, nullptr) << robot << " " << effect;
      ASSERT_NE(large, nullptr) << robot << " " << effect;
      for (const BatteryCase* c : {small, large}) {
        EXPECT_EQ(c->kind, CaseKind::kSingle) << c->id;
        ASSERT_EQ(c->expected.size(), 1U) << c->id;
        EXPECT_EQ(c->expected[0].effect, effect) << c->id;
        EXPECT_TRUE(active_outside_effects(c->spec.outside).empty()) << c->id;
      }
      EXPECT_GT(size_of(large->expected[0]), size_of(small->expected[0])) << robot << " " << effect;
    }
  }
}

TEST(Battery, AccelLimitCasesLeaveTheLimitsOutOfTheModel) {
  for (const BatteryCase& c : battery()) {
    const bool names_accel =
        std::any_of(c.expected.begin(), c.expected.end(),
                    [](const ExpectedEffect& e) { return e.effect == "accel_limit"; });
    const std::string yaml = nominal_model_yaml(c.spec);
    const RobotModel m = parse_robot_model(yaml, c.id);
    EXPECT_EQ(names_accel, !m.limits.linear_acceleration_mps2.has_value()) << c.id;
    // Passive casters have no steering motor, so no steering rate limit to state.
    EXPECT_EQ(c.spec.robot == Robot::kSwpc4 && c.spec.steering != Steering::kSelfAligning,
              m.limits.steering_rate_radps.has_value())
        << c.id;
  }
}

TEST(Battery, HasCleanRunsPairsAndOutsideEffectsOnBothRobots) {
  std::map<std::string, std::set<std::uint64_t>> clean_seeds;
  std::map<std::string, std::set<std::string>> outside_kinds;
  int pairs = 0;
  bool self_aligning_clean = false;
  for (const BatteryCase& c : battery()) {
    switch (c.kind) {
      case CaseKind::kClean:
        EXPECT_TRUE(c.expected.empty()) << c.id;
        EXPECT_TRUE(active_outside_effects(c.spec.outside).empty()) << c.id;
        clean_seeds[c.robot].insert(c.spec.seed);
        self_aligning_clean |= c.spec.steering == Steering::kSelfAligning;
        break;
      case CaseKind::kPair: {
        ++pairs;
        ASSERT_EQ(c.expected.size(), 2U) << c.id;
        const std::string names = c.id.substr(c.id.rfind('/') + 1);
        std::set<std::string> in_id{names.substr(0, names.find('+')),
                                    names.substr(names.find('+') + 1)};
        EXPECT_EQ(in_id, (std::set<std::string>{c.expected[0].effect, c.expected[1].effect}))
            << c.id;
        break;
      }
      case CaseKind::kOutside: {
        EXPECT_TRUE(c.expected.empty()) << c.id;
        const std::vector<std::string> active = active_outside_effects(c.spec.outside);
        ASSERT_EQ(active.size(), 1U) << c.id;
        EXPECT_EQ(c.id, c.robot + "/outside/" + active[0]);
        outside_kinds[c.robot].insert(active[0]);
        break;
      }
      case CaseKind::kSingle: break;
    }
    // Slip noise and sensor noise are always on in the battery.
    EXPECT_EQ(c.spec.noise.slip_std, 0.002) << c.id;
    EXPECT_EQ(c.spec.noise.gyro_noise_rad_s, 0.002) << c.id;
  }
  for (const char* robot : {"docent", "swpc4"}) {
    EXPECT_GE(clean_seeds[robot].size(), 3U) << robot;
    EXPECT_GE(outside_kinds[robot].size(), 3U) << robot;
  }
  EXPECT_TRUE(self_aligning_clean);
  EXPECT_GE(pairs, 4);
  for (const char* id :
       {"docent/pair/gyro_bias+wheel_radius", "docent/pair/track_width+actuator_lag",
        "swpc4/pair/steering_offset+sensor_latency", "swpc4/pair/wheel_radius+accel_limit"}) {
    EXPECT_NE(find_case(id), nullptr) << id;
  }
}

TEST(Battery, CleanRunsOfARobotDriveDifferentTours) {
  std::map<std::string, std::vector<std::vector<TourSegment>>> tours;
  for (const BatteryCase& c : battery()) {
    if (c.kind != CaseKind::kClean) continue;
    tours[c.robot].push_back(
        make_tour(c.spec.robot, c.spec.steering, c.spec.seed, c.spec.duration_s));
  }
  for (const auto& [robot, list] : tours) {
    for (std::size_t i = 0; i < list.size(); ++i) {
      for (std::size_t j = i + 1; j < list.size(); ++j) {
        const bool same =
            list[i].size() == list[j].size() &&
            std::equal(list[i].begin(), list[i].end(), list[j].begin(),
                       [](const TourSegment& a, const TourSegment& b) {
                         return a.start_s == b.start_s && a.target.vx_mps == b.target.vx_mps;
                       });
        EXPECT_FALSE(same) << robot << " tours " << i << " and " << j;
      }
    }
  }
}

TEST(Battery, SubsetIsTheEightRepresentativeCases) {
  const std::vector<BatteryCase> subset = battery_subset();
  std::vector<std::string> ids;
  ids.reserve(subset.size());
  for (const BatteryCase& c : subset) ids.push_back(c.id);
  EXPECT_EQ(ids, (std::vector<std::string>{"docent/clean/1", "swpc4/clean/1",
                                           "docent/gyro_bias/large", "swpc4/steering_offset/large",
                                           "docent/actuator_lag/large", "swpc4/accel_limit/large",
                                           "docent/pair/track_width+actuator_lag",
                                           "swpc4/outside/floor_drift"}));
}

// Every case, shortened, writes files the project's readers accept.
TEST(Battery, EveryCaseWritesFilesTheProjectsReadersAccept) {
  for (const BatteryCase& c : battery()) {
    RunSpec spec = c.spec;
    spec.duration_s = 6.0;
    const GeneratedRun run = generate(spec);
    std::istringstream in(run.run_csv);
    const RunLog log = parse_run_log(in, c.id);
    EXPECT_EQ(log.samples.size(), 600U) << c.id;
    EXPECT_EQ(parse_robot_model(run.nominal_model_yaml, c.id).name, c.robot) << c.id;
  }
}

}  // namespace
}  // namespace swivel::independent
