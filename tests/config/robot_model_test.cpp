// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "swivel/config/config_error.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel {
namespace {

const std::string docent_yaml = R"(name: docent
drivetrain: differential
differential:
  wheel_radius_left_m: 0.075
  wheel_radius_right_m: 0.0752
  track_width_m: 0.40
sensors:
  wheel_encoder_counts_per_rev: 4096
  gyro: {scale: 1.01, bias_rad_s: 0.006, noise_rad_s: 0.002}
  motion_capture: {position_noise_m: 0.0003, yaw_noise_rad: 0.001}
effects: {}
)";

const std::string swpc_yaml = R"(name: "cart 7"
drivetrain: swpc
swpc:
  modules:
    - {x_m: 0.215, y_m: 0.125, steering_offset_rad: 0.01, caster_offset_m: 0.020, wheel_radius_m: 0.055}
    - {x_m: -0.215, y_m: -0.125, steering_offset_rad: -0.02, caster_offset_m: 0.021, wheel_radius_m: 0.0551}
sensors:
  steering_encoder_counts_per_rev: 8192
  motion_capture: {rate_hz: 120}
effects:
  gyro_bias: {bias_rad_s: 0.006}
  slip: {ratio: 0.1, onset_mps: 0.3}
)";

std::string error_of(const std::string& text) {
  try {
    parse_robot_model(text, "robot.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return {};
}

void expect_same(const RobotModel& a, const RobotModel& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.drivetrain, b.drivetrain);
  EXPECT_EQ(a.differential.wheel_radius_left_m, b.differential.wheel_radius_left_m);
  EXPECT_EQ(a.differential.wheel_radius_right_m, b.differential.wheel_radius_right_m);
  EXPECT_EQ(a.differential.track_width_m, b.differential.track_width_m);
  ASSERT_EQ(a.modules.size(), b.modules.size());
  for (std::size_t i = 0; i < a.modules.size(); ++i) {
    EXPECT_EQ(a.modules[i].x_m, b.modules[i].x_m);
    EXPECT_EQ(a.modules[i].y_m, b.modules[i].y_m);
    EXPECT_EQ(a.modules[i].steering_offset_rad, b.modules[i].steering_offset_rad);
    EXPECT_EQ(a.modules[i].caster_offset_m, b.modules[i].caster_offset_m);
    EXPECT_EQ(a.modules[i].wheel_radius_m, b.modules[i].wheel_radius_m);
  }
  EXPECT_EQ(a.sensors.wheel_encoder_counts_per_rev, b.sensors.wheel_encoder_counts_per_rev);
  EXPECT_EQ(a.sensors.steering_encoder_counts_per_rev, b.sensors.steering_encoder_counts_per_rev);
  EXPECT_EQ(a.sensors.gyro.scale, b.sensors.gyro.scale);
  EXPECT_EQ(a.sensors.gyro.bias_rad_s, b.sensors.gyro.bias_rad_s);
  EXPECT_EQ(a.sensors.gyro.noise_rad_s, b.sensors.gyro.noise_rad_s);
  EXPECT_EQ(a.sensors.motion_capture.position_noise_m, b.sensors.motion_capture.position_noise_m);
  EXPECT_EQ(a.sensors.motion_capture.yaw_noise_rad, b.sensors.motion_capture.yaw_noise_rad);
  EXPECT_EQ(a.sensors.motion_capture.rate_hz, b.sensors.motion_capture.rate_hz);
  EXPECT_EQ(a.limits.linear_velocity_mps, b.limits.linear_velocity_mps);
  EXPECT_EQ(a.limits.angular_velocity_radps, b.limits.angular_velocity_radps);
  EXPECT_EQ(a.limits.linear_acceleration_mps2, b.limits.linear_acceleration_mps2);
  EXPECT_EQ(a.limits.angular_acceleration_radps2, b.limits.angular_acceleration_radps2);
  EXPECT_EQ(a.limits.linear_jerk_mps3, b.limits.linear_jerk_mps3);
  EXPECT_EQ(a.limits.angular_jerk_radps3, b.limits.angular_jerk_radps3);
  EXPECT_EQ(a.limits.steering_rate_radps, b.limits.steering_rate_radps);
  EXPECT_EQ(a.effects, b.effects);
}

TEST(RobotModel, ParsesDifferentialModel) {
  const RobotModel m = parse_robot_model(docent_yaml, "docent.yaml");
  EXPECT_EQ(m.name, "docent");
  EXPECT_EQ(m.drivetrain, DrivetrainKind::kDifferential);
  EXPECT_EQ(m.differential.wheel_radius_right_m, 0.0752);
  EXPECT_EQ(m.sensors.gyro.bias_rad_s, 0.006);
  EXPECT_EQ(m.sensors.motion_capture.rate_hz, 100.0);  // default
  EXPECT_EQ(m.module_count(), 2U);
  EXPECT_TRUE(m.effects.empty());
  EXPECT_EQ(m.source_file, "docent.yaml");
}

TEST(RobotModel, ParsesSwpcModelWithEffects) {
  const RobotModel m = parse_robot_model(swpc_yaml, "cart.yaml");
  EXPECT_EQ(m.name, "cart 7");
  ASSERT_EQ(m.module_count(), 2U);
  EXPECT_EQ(m.modules[1].x_m, -0.215);
  EXPECT_EQ(m.modules[1].wheel_radius_m, 0.0551);
  EXPECT_EQ(m.sensors.steering_encoder_counts_per_rev, 8192);
  EXPECT_EQ(m.sensors.motion_capture.rate_hz, 120.0);
  EXPECT_EQ(m.effects.at("slip").at("onset_mps"), 0.3);
  EXPECT_EQ(m.effects.at("gyro_bias").at("bias_rad_s"), 0.006);
}

TEST(RobotModel, SaveThenLoadGivesTheSameModel) {
  for (const std::string& text : {docent_yaml, swpc_yaml}) {
    const RobotModel original = parse_robot_model(text, "in.yaml");
    const std::string path = testing::TempDir() + "/saved_model.yaml";
    save_robot_model(original, path);
    expect_same(load_robot_model(path), original);
    std::remove(path.c_str());
  }
}

TEST(RobotModel, WritesShortestExactNumbers) {
  const std::string yaml = robot_model_to_yaml(parse_robot_model(docent_yaml, "in.yaml"));
  EXPECT_NE(yaml.find("  wheel_radius_left_m: 0.075\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("effects: {}\n"), std::string::npos) << yaml;
}

TEST(RobotModel, RepositoryDocentModelLoads) {
  const RobotModel m =
      load_robot_model(std::string(SWIVEL_SOURCE_DIR) + "/config/robots/docent.yaml");
  EXPECT_EQ(m.name, "docent");
  EXPECT_EQ(m.differential.track_width_m, 0.40);
  EXPECT_EQ(m.differential.wheel_radius_left_m, 0.075);
  EXPECT_EQ(m.sensors.gyro.noise_rad_s, 0.002);
}

TEST(RobotModel, RejectsUnknownKeyWithKnownKeys) {
  std::string text = docent_yaml;
  text.insert(text.find("  track_width_m"), "  tire_pressure_bar: 2\n");
  EXPECT_EQ(error_of(text),
            "robot.yaml:6:3: differential.tire_pressure_bar: unknown key (known: "
            "wheel_radius_left_m, wheel_radius_right_m, track_width_m)");
}

TEST(RobotModel, MisspeltRequiredKeyIsPointedAt) {
  std::string text = docent_yaml;
  text.replace(text.find("  track_width_m"), 15, "  track_widht_m");
  EXPECT_EQ(error_of(text),
            "robot.yaml:4:3: differential: missing required key 'track_width_m' (expected a "
            "number); is 'track_widht_m' on line 6 a misspelling?");
}

TEST(RobotModel, RejectsMissingRequiredKey) {
  std::string text = docent_yaml;
  text.erase(text.find("  wheel_radius_left_m: 0.075\n"), 29);
  EXPECT_EQ(error_of(text),
            "robot.yaml:4:3: differential: missing required key 'wheel_radius_left_m' "
            "(expected a number)");
}

TEST(RobotModel, RejectsNonPositiveGeometry) {
  std::string text = docent_yaml;
  text.replace(text.find("0.40"), 4, "-0.4");
  EXPECT_EQ(error_of(text),
            "robot.yaml:6:3: differential.track_width_m: expected a positive number, got -0.4");
}

TEST(RobotModel, CountsPerRevolutionAreRealValued) {
  std::string text = docent_yaml;
  text.replace(text.find("4096"), 4, "2796.8");  // a 43.7:1 gear on a 64-count encoder
  const RobotModel m = parse_robot_model(text, "robot.yaml");
  EXPECT_EQ(m.sensors.wheel_encoder_counts_per_rev, 2796.8);
  expect_same(m, parse_robot_model(robot_model_to_yaml(m), "again.yaml"));
}

TEST(RobotModel, RejectsCountsPerRevolutionThatAreNotPositiveAndFinite) {
  for (const char* bad : {"0", "-64", ".nan", ".inf", "many"}) {
    std::string text = docent_yaml;
    text.replace(text.find("4096"), 4, bad);
    EXPECT_NE(
        error_of(text).find("robot.yaml:8:3: sensors.wheel_encoder_counts_per_rev: expected "),
        std::string::npos)
        << bad << ": " << error_of(text);
  }
}

TEST(RobotModel, RejectsSectionThatDoesNotMatchDrivetrain) {
  std::string text = docent_yaml;
  text.replace(text.find("drivetrain: differential"), 24, "drivetrain: swpc");
  EXPECT_EQ(error_of(text),
            "robot.yaml:3:1: differential: section does not match drivetrain 'swpc' "
            "(expected a 'swpc' section)");
}

TEST(RobotModel, RejectsUnknownDrivetrain) {
  std::string text = docent_yaml;
  text.replace(text.find("drivetrain: differential"), 24, "drivetrain: tank");
  EXPECT_EQ(error_of(text),
            "robot.yaml:2:1: drivetrain: expected one of differential, swpc, got 'tank'");
}

TEST(RobotModel, RejectsSwpcWithOneModule) {
  std::string text = swpc_yaml;
  text.erase(text.find("    - {x_m: -0.215"),
             text.find("sensors:") - text.find("    - {x_m: -0.215"));
  EXPECT_EQ(error_of(text),
            "robot.yaml:4:3: swpc.modules: expected between 2 and 16 modules, got 1");
}

TEST(RobotModel, RejectsUnknownKeyInModule) {
  std::string text = swpc_yaml;
  text.replace(text.find("wheel_radius_m: 0.0551"), 14, "wheel_diameter_m");
  EXPECT_EQ(error_of(text),
            "robot.yaml:6:7: swpc.modules[1]: missing required key 'wheel_radius_m' (expected a "
            "number)");
  text.replace(text.find("wheel_diameter_m"), 16, "wheel_radius_m: 0.055, camber_rad");
  EXPECT_EQ(error_of(text),
            "robot.yaml:6:109: swpc.modules[1].camber_rad: unknown key (known: x_m, y_m, "
            "steering_offset_rad, caster_offset_m, wheel_radius_m)");
}

TEST(RobotModel, RejectsNonNumericEffectParameter) {
  std::string text = swpc_yaml;
  text.replace(text.find("0.006}"), 5, "large");
  EXPECT_EQ(error_of(text),
            "robot.yaml:11:15: effects.gyro_bias.bias_rad_s: expected a number, got 'large'");
}

TEST(RobotModel, EffectNamesAreIdentifiers) {
  std::string text = swpc_yaml;
  text.replace(text.find("gyro_bias"), 9, "\"gyro bias\"");
  EXPECT_EQ(error_of(text),
            "robot.yaml:11:3: effects: effect names must be 1 to 64 letters, digits, '_', '-' or "
            "'.' (like gyro_bias or bias_rad_s)");

  // Bounded so that, escaped and written back, any name stays inside YAML's limit on a key.
  text = swpc_yaml;
  text.replace(text.find("bias_rad_s"), 10, "\"" + std::string(65, 'b') + "\"");
  EXPECT_EQ(error_of(text),
            "robot.yaml:11:14: effects.gyro_bias: effect parameter names must be 1 to 64 letters, "
            "digits, '_', '-' or '.' (like gyro_bias or bias_rad_s)");

  text = swpc_yaml;
  text.replace(text.find("bias_rad_s"), 10, std::string(64, 'b'));
  const RobotModel longest = parse_robot_model(text, "robot.yaml");
  expect_same(longest, parse_robot_model(robot_model_to_yaml(longest), "written.yaml"));
}

const std::string swpc_limits_yaml = R"(limits:
  linear_acceleration_mps2: 0.6
  angular_acceleration_radps2: 2.0
  steering_rate_radps: 6.0
  linear_jerk_mps3: 5
)";

TEST(RobotModel, LimitsAreOptionalAndRoundTrip) {
  const RobotModel without = parse_robot_model(swpc_yaml, "cart.yaml");
  EXPECT_FALSE(without.limits.any());
  EXPECT_EQ(robot_model_to_yaml(without).find("limits:"), std::string::npos);

  const RobotModel m = parse_robot_model(swpc_yaml + swpc_limits_yaml, "cart.yaml");
  EXPECT_EQ(m.limits.linear_acceleration_mps2, 0.6);
  EXPECT_EQ(m.limits.angular_acceleration_radps2, 2.0);
  EXPECT_EQ(m.limits.steering_rate_radps, 6.0);
  EXPECT_EQ(m.limits.linear_jerk_mps3, 5.0);
  EXPECT_FALSE(m.limits.linear_velocity_mps.has_value());
  EXPECT_FALSE(m.limits.angular_jerk_radps3.has_value());
  expect_same(parse_robot_model(robot_model_to_yaml(m), "again.yaml"), m);
}

TEST(RobotModel, RejectsBadLimits) {
  std::string text = swpc_yaml + swpc_limits_yaml;
  text.replace(text.find("0.6"), 3, "0");
  EXPECT_EQ(error_of(text),
            "robot.yaml:14:3: limits.linear_acceleration_mps2: expected a positive number, got 0");
  EXPECT_EQ(error_of(swpc_yaml + "limits: {max_speed: 1}\n"),
            "robot.yaml:13:10: limits.max_speed: unknown key (known: linear_velocity_mps, "
            "angular_velocity_radps, linear_acceleration_mps2, angular_acceleration_radps2, "
            "linear_jerk_mps3, angular_jerk_radps3, steering_rate_radps)");
  EXPECT_EQ(error_of(docent_yaml + "limits: {steering_rate_radps: 6}\n"),
            "robot.yaml:12:10: limits.steering_rate_radps: applies to swpc robots only (this one "
            "is differential)");
}

TEST(RobotModel, RejectsBrokenYamlWithLineAndColumn) {
  const std::string error = error_of("name: docent\ndifferential: {track_width_m: 0.4\n");
  EXPECT_EQ(error.rfind("robot.yaml:", 0), 0U) << error;
  EXPECT_NE(error.find(": invalid YAML: "), std::string::npos) << error;
  EXPECT_NE(error.find("robot.yaml:3:1:"), std::string::npos) << error;
}

TEST(RobotModel, MissingFileNamesIt) {
  try {
    load_robot_model("/nonexistent/robot.yaml");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/robot.yaml: cannot read robot model file");
  }
}

}  // namespace
}  // namespace swivel
