// SPDX-License-Identifier: Apache-2.0
// fold_effects(): the model the daemon loads must be the world the simulator builds from the
// model with the named effects, parameter for parameter (sim::resolve_plant as the reference).

#include "swivel/model_gap/fold_effects.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <span>
#include <string>
#include <string_view>

#include "gap_fixtures.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {
namespace {

void expect_same_plant(const sim::PlantParams& a, const sim::PlantParams& b,
                       const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(a.drivetrain, b.drivetrain);
  EXPECT_EQ(a.module_count, b.module_count);
  EXPECT_EQ(a.differential.wheel_radius_left_m, b.differential.wheel_radius_left_m);
  EXPECT_EQ(a.differential.wheel_radius_right_m, b.differential.wheel_radius_right_m);
  EXPECT_EQ(a.differential.track_width_m, b.differential.track_width_m);
  for (std::size_t i = 0; i < kMaxModules; ++i) {
    EXPECT_EQ(a.modules[i].x_m, b.modules[i].x_m) << "module " << i;
    EXPECT_EQ(a.modules[i].y_m, b.modules[i].y_m) << "module " << i;
    EXPECT_EQ(a.modules[i].steering_offset_rad, b.modules[i].steering_offset_rad) << "module " << i;
    EXPECT_EQ(a.modules[i].caster_offset_m, b.modules[i].caster_offset_m) << "module " << i;
    EXPECT_EQ(a.modules[i].wheel_radius_m, b.modules[i].wheel_radius_m) << "module " << i;
  }
  EXPECT_EQ(a.sensors.gyro.scale, b.sensors.gyro.scale);
  EXPECT_EQ(a.sensors.gyro.bias_rad_s, b.sensors.gyro.bias_rad_s);
  EXPECT_EQ(a.sensors.gyro.noise_rad_s, b.sensors.gyro.noise_rad_s);
  EXPECT_EQ(a.sensors.wheel_encoder_counts_per_rev, b.sensors.wheel_encoder_counts_per_rev);
  EXPECT_EQ(a.sensors.steering_encoder_counts_per_rev, b.sensors.steering_encoder_counts_per_rev);
  EXPECT_EQ(a.slip_gain_per_radps2, b.slip_gain_per_radps2);
  EXPECT_EQ(a.track_spin_scale, b.track_spin_scale);
  EXPECT_EQ(a.actuator_time_constant_s, b.actuator_time_constant_s);
  EXPECT_EQ(a.steering_time_constant_s, b.steering_time_constant_s);
  EXPECT_EQ(a.sensor_delay_s, b.sensor_delay_s);
  EXPECT_EQ(a.limits.linear_acceleration_mps2, b.limits.linear_acceleration_mps2);
}

// A value unlike the identity for every parameter of every effect: scales 1 + 0.01 k,
// additive ones 0.003 k (k counts the parameters), so that no two coincide.
EffectParams unlike_identity(const sim::EffectInfo& effect, int& k) {
  EffectParams params;
  for (const sim::EffectParamInfo& p : effect.params) {
    ++k;
    params[p.key] = p.identity == 1.0 ? 1.0 + 0.01 * k : 0.003 * k;
  }
  return params;
}

// A model as the workflow augments it: a calibrated nominal model (gyro scale and bias,
// steering offsets not zero) with one effect, or all of them.
RobotModel calibrated(const std::string& name) {
  RobotModel m = testing::robot(name);
  m.sensors.gyro.scale = 1.01;
  m.sensors.gyro.bias_rad_s = -0.002;
  for (std::size_t i = 0; i < m.modules.size(); ++i)
    m.modules[i].steering_offset_rad = 0.05 * static_cast<double>(i);
  return m;
}

constexpr std::array<std::string_view, 7> kFoldable = {
    "gyro_bias",     "gyro_scale",      "wheel_radius", "track_width",
    "caster_offset", "steering_offset", "module_layout"};
constexpr std::array<std::string_view, 5> kKept = {"slip", "actuator_lag", "steering_lag",
                                                   "sensor_latency", "track_scrub"};

bool contains(std::span<const std::string_view> names, std::string_view name) {
  return std::ranges::find(names, name) != names.end();
}

class FoldEffects : public ::testing::TestWithParam<const char*> {};

TEST_P(FoldEffects, EachEffectFoldsIntoTheParameterTheWorldChangesAndNothingElse) {
  const RobotModel base = calibrated(GetParam());
  int k = 0;
  for (const sim::EffectInfo& effect : sim::effect_library(base)) {
    RobotModel augmented = base;
    augmented.effects[effect.name] = unlike_identity(effect, k);
    const FoldResult f = fold_effects(augmented);
    expect_same_plant(sim::resolve_plant(f.model), sim::resolve_plant(augmented), effect.name);
    if (contains(kFoldable, effect.name)) {
      EXPECT_TRUE(f.model.effects.empty()) << effect.name;
      EXPECT_TRUE(f.kept.empty()) << effect.name;
      // One line per parameter changed: module_layout moves both coordinates of every module.
      const std::size_t lines =
          effect.name == "module_layout" ? 2 * base.modules.size() : effect.params.size();
      EXPECT_EQ(f.folded.size(), lines) << effect.name;
      // The model really changed: without the effect its world is another one.
      const sim::PlantParams nominal = sim::resolve_plant(base);
      const sim::PlantParams folded = sim::resolve_plant(f.model);
      EXPECT_TRUE(nominal.sensors.gyro.bias_rad_s != folded.sensors.gyro.bias_rad_s ||
                  nominal.sensors.gyro.scale != folded.sensors.gyro.scale ||
                  nominal.differential.wheel_radius_left_m !=
                      folded.differential.wheel_radius_left_m ||
                  nominal.differential.track_width_m != folded.differential.track_width_m ||
                  nominal.modules[1].wheel_radius_m != folded.modules[1].wheel_radius_m ||
                  nominal.modules[1].caster_offset_m != folded.modules[1].caster_offset_m ||
                  nominal.modules[1].steering_offset_rad != folded.modules[1].steering_offset_rad ||
                  nominal.modules[1].x_m != folded.modules[1].x_m ||
                  nominal.modules[1].y_m != folded.modules[1].y_m)
          << effect.name;
    } else {
      ASSERT_TRUE(contains(kKept, effect.name)) << effect.name << ": neither folded nor kept";
      EXPECT_EQ(f.model.effects, augmented.effects) << effect.name;
      ASSERT_EQ(f.kept.size(), 1U) << effect.name;
      EXPECT_EQ(f.kept[0].rfind(effect.name + ": the robot model has no", 0), 0U) << f.kept[0];
      EXPECT_TRUE(f.folded.empty());
    }
  }
}

TEST_P(FoldEffects, AllEffectsTogetherAndThroughTheModelFile) {
  RobotModel augmented = calibrated(GetParam());
  augmented.limits.linear_acceleration_mps2 = 0.7;  // a fitted limit stays where it is
  int k = 0;
  for (const sim::EffectInfo& effect : sim::effect_library(augmented)) {
    augmented.effects[effect.name] = unlike_identity(effect, k);
  }
  const FoldResult f = fold_effects(augmented);
  expect_same_plant(sim::resolve_plant(f.model), sim::resolve_plant(augmented), "in memory");
  // What the daemon loads: the YAML written and read back.
  const RobotModel loaded = parse_robot_model(robot_model_to_yaml(f.model), "folded.yaml");
  expect_same_plant(sim::resolve_plant(loaded), sim::resolve_plant(augmented), "from the file");
  for (const auto& [name, params] : f.model.effects) {
    EXPECT_TRUE(contains(kKept, name)) << name << " stayed in effects:";
  }
  EXPECT_EQ(f.kept.size(), f.model.effects.size());
}

INSTANTIATE_TEST_SUITE_P(BothDrivetrains, FoldEffects, ::testing::Values("docent", "swpc4"));

TEST(FoldEffectsLine, SaysWhatWentWhere) {
  RobotModel m = testing::robot("docent");
  m.effects["gyro_bias"]["bias_rad_s"] = 0.004;
  m.effects["sensor_latency"]["delay_s"] = 0.02;
  const FoldResult f = fold_effects(m);
  ASSERT_EQ(f.folded.size(), 1U);
  EXPECT_EQ(f.folded[0], "gyro_bias.bias_rad_s = 0.004 -> sensors.gyro.bias_rad_s 0 -> 0.004");
  ASSERT_EQ(f.kept.size(), 1U);
  EXPECT_EQ(f.kept[0].rfind("sensor_latency: the robot model has no latency parameter", 0), 0U)
      << f.kept[0];
  EXPECT_EQ(f.model.sensors.gyro.bias_rad_s, 0.004);
}

// The daemon's swpc drivetrain reads the module positions from `swpc.modules`: a layout
// effect moves every steering axis there, x by the longitudinal and y by the lateral scale.
TEST(FoldEffectsLine, AModuleLayoutMovesEveryModuleInTheModelFile) {
  RobotModel m = testing::robot("swpc4");
  m.effects["module_layout"]["lateral_scale"] = 1.02;
  m.effects["module_layout"]["longitudinal_scale"] = 0.99;
  const FoldResult f = fold_effects(m);
  EXPECT_TRUE(f.kept.empty());
  EXPECT_TRUE(f.model.effects.empty());
  ASSERT_EQ(f.folded.size(), 8U);
  EXPECT_EQ(
      f.folded[0].rfind(
          "module_layout.longitudinal_scale = 0.99 -> swpc.modules[0].x_m 0.215 -> 0.2128", 0),
      0U)
      << f.folded[0];
  EXPECT_EQ(f.folded[7].rfind(
                "module_layout.lateral_scale = 1.02 -> swpc.modules[3].y_m 0.125 -> 0.1275", 0),
            0U)
      << f.folded[7];
  const RobotModel loaded = parse_robot_model(robot_model_to_yaml(f.model), "folded.yaml");
  ASSERT_EQ(loaded.modules.size(), m.modules.size());
  for (std::size_t i = 0; i < m.modules.size(); ++i) {
    EXPECT_DOUBLE_EQ(loaded.modules[i].x_m, m.modules[i].x_m * 0.99) << "module " << i;
    EXPECT_DOUBLE_EQ(loaded.modules[i].y_m, m.modules[i].y_m * 1.02) << "module " << i;
  }
  expect_same_plant(sim::resolve_plant(loaded), sim::resolve_plant(m), "from the file");
}

TEST(FoldEffectsLine, AValueTheModelFileCannotHoldStaysAnEffect) {
  RobotModel m = testing::robot("docent");
  m.sensors.gyro.scale = 1.9;
  m.effects["gyro_scale"]["scale"] = 1.2;  // 2.28: the reader takes scales in [0.5, 2]
  const FoldResult f = fold_effects(m);
  EXPECT_TRUE(f.folded.empty());
  ASSERT_EQ(f.kept.size(), 1U);
  EXPECT_NE(f.kept[0].find("sensors.gyro.scale would be 2.28"), std::string::npos) << f.kept[0];
  EXPECT_EQ(f.model.sensors.gyro.scale, 1.9);
  expect_same_plant(sim::resolve_plant(f.model), sim::resolve_plant(m), "kept");
}

TEST(FoldEffectsLine, AnInvalidEffectIsRefusedWithItsName) {
  RobotModel m = testing::robot("docent");
  m.effects["caster_offset"]["module_1_scale"] = 1.1;
  try {
    (void)fold_effects(m);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("effects.caster_offset"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace swivel::model_gap
