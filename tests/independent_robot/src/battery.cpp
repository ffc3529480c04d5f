// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/battery.hpp"

#include <initializer_list>
#include <stdexcept>

#include "swivel/independent/outside_effects.hpp"

namespace swivel::independent {
namespace {

constexpr double kRunS = 120.0;

struct CaseBuilder {
  std::vector<BatteryCase> cases;

  void add(const std::string& id, Robot robot, CaseKind kind, const std::string& description,
           std::uint64_t seed, std::initializer_list<const char*> truth,
           ModelLimits limits = ModelLimits::kAll, std::initializer_list<const char*> outside = {},
           Steering steering = Steering::kPowered) {
    BatteryCase c;
    c.id = id;
    c.robot = robot_name(robot);
    c.kind = kind;
    c.description = description;
    c.spec.robot = robot;
    c.spec.steering = steering;
    c.spec.seed = seed;
    c.spec.duration_s = kRunS;
    c.spec.model_limits = limits;
    for (const char* a : truth) set_true_effect(c.spec, a);
    for (const char* a : outside) set_outside_effect(c.spec, a);
    validate(c.spec);
    c.expected = expected_effects(c.spec);
    cases.push_back(std::move(c));
  }

  void single(const std::string& robot_effect_size, Robot robot, const std::string& description,
              std::uint64_t seed, std::initializer_list<const char*> truth,
              ModelLimits limits = ModelLimits::kAll) {
    add(robot_name(robot) + "/" + robot_effect_size, robot, CaseKind::kSingle, description, seed,
        truth, limits);
  }
};

std::vector<BatteryCase> build() {
  const Robot d = Robot::kDocent;
  const Robot s = Robot::kSwpc4;
  CaseBuilder b;

  // Clean: the true robot is the nominal one; only noise and the random-walk slip.
  b.add("docent/clean/1", d, CaseKind::kClean, "nominal docent, tour and noise of seed 11", 11, {});
  b.add("docent/clean/2", d, CaseKind::kClean, "nominal docent, tour and noise of seed 12", 12, {});
  b.add("docent/clean/3", d, CaseKind::kClean, "nominal docent, tour and noise of seed 13", 13, {});
  b.add("swpc4/clean/1", s, CaseKind::kClean, "nominal swpc4, tour and noise of seed 21", 21, {});
  b.add("swpc4/clean/2", s, CaseKind::kClean, "nominal swpc4, tour and noise of seed 22", 22, {});
  b.add("swpc4/clean/3", s, CaseKind::kClean, "nominal swpc4, tour and noise of seed 23", 23, {});
  b.add("swpc4/clean/self_aligning", s, CaseKind::kClean,
        "nominal swpc4 with passive, self-aligning casters (steering motors off)", 24, {},
        ModelLimits::kAll, {}, Steering::kSelfAligning);

  // docent, one library effect at two sizes.
  b.single("gyro_bias/small", d, "gyro bias +0.002 rad/s", 101, {"gyro_bias.bias_rad_s=0.002"});
  b.single("gyro_bias/large", d, "gyro bias +0.006 rad/s", 102, {"gyro_bias.bias_rad_s=0.006"});
  b.single("gyro_scale/small", d, "gyro reads 1.005 x the true rate", 103,
           {"gyro_scale.scale=1.005"});
  b.single("gyro_scale/large", d, "gyro reads 1.02 x the true rate", 104,
           {"gyro_scale.scale=1.02"});
  b.single("wheel_radius/small", d, "right wheel 0.5 % smaller than the model", 105,
           {"wheel_radius.right_scale=0.995"});
  b.single("wheel_radius/large", d, "left wheel 1.8 % larger than the model", 106,
           {"wheel_radius.left_scale=1.018"});
  b.single("track_width/small", d, "track 1 % wider than the model", 107,
           {"track_width.scale=1.01"});
  b.single("track_width/large", d, "track 4 % wider than the model", 108,
           {"track_width.scale=1.04"});
  b.single("sensor_latency/small", d, "encoders and gyro 0.02 s late", 109,
           {"sensor_latency.delay_s=0.02"});
  b.single("sensor_latency/large", d, "encoders and gyro 0.06 s late", 110,
           {"sensor_latency.delay_s=0.06"});
  b.single("actuator_lag/small", d, "wheel drives lag their setpoints by 0.03 s", 111,
           {"actuator_lag.time_constant_s=0.03"});
  b.single("actuator_lag/large", d, "wheel drives lag their setpoints by 0.08 s", 112,
           {"actuator_lag.time_constant_s=0.08"});
  b.single("accel_limit/small", d,
           "controller limits acceleration to 0.6 m/s^2, 2 rad/s^2; the model states none", 113, {},
           ModelLimits::kNone);
  b.single("accel_limit/large", d,
           "controller limits acceleration to 0.3 m/s^2, 1 rad/s^2; the model states none", 114,
           {"accel_limit.linear_mps2=0.3", "accel_limit.angular_radps2=1.0"}, ModelLimits::kNone);
  b.single("slip/small", d, "acceleration slip, gain 0.001 per rad/s^2", 115,
           {"slip.gain_per_radps2=0.001"});
  b.single("slip/large", d, "acceleration slip, gain 0.003 per rad/s^2", 116,
           {"slip.gain_per_radps2=0.003"});

  // swpc4, one library effect at two sizes.
  b.single("gyro_bias/small", s, "gyro bias -0.002 rad/s", 201, {"gyro_bias.bias_rad_s=-0.002"});
  b.single("gyro_bias/large", s, "gyro bias -0.006 rad/s", 202, {"gyro_bias.bias_rad_s=-0.006"});
  b.single("gyro_scale/small", s, "gyro reads 0.995 x the true rate", 203,
           {"gyro_scale.scale=0.995"});
  b.single("gyro_scale/large", s, "gyro reads 0.98 x the true rate", 204,
           {"gyro_scale.scale=0.98"});
  b.single("wheel_radius/small", s, "module 2 wheel 0.5 % smaller than the model", 205,
           {"wheel_radius.module_2_scale=0.995"});
  b.single("wheel_radius/large", s, "module 1 wheel 1.8 % larger, module 3 1.8 % smaller", 206,
           {"wheel_radius.module_1_scale=1.018", "wheel_radius.module_3_scale=0.982"});
  b.single("caster_offset/small", s, "module 3 caster offset 15 % longer than the model", 207,
           {"caster_offset.module_3_scale=1.15"});
  b.single("caster_offset/large", s, "caster offsets x (1.2, 0.9, 1.1, 1.25)", 208,
           {"caster_offset.module_1_scale=1.2", "caster_offset.module_2_scale=0.9",
            "caster_offset.module_3_scale=1.1", "caster_offset.module_4_scale=1.25"});
  // Offsets of both signs that do not cancel: their mean turns the odometry's direction of
  // travel, their differences make the modules fight (as the paper's Table 4 robot, whose
  // offsets are all positive, would).
  b.single("steering_offset/small", s, "steering offsets (0.4, -0.3, 0.6, 0.5) degrees", 209,
           {"steering_offset.module_1_rad=0.007", "steering_offset.module_2_rad=-0.0052",
            "steering_offset.module_3_rad=0.0105", "steering_offset.module_4_rad=0.0087"});
  b.single("steering_offset/large", s, "steering offsets (1.2, -0.6, 0.9, 1.5) degrees", 210,
           {"steering_offset.module_1_rad=0.021", "steering_offset.module_2_rad=-0.0105",
            "steering_offset.module_3_rad=0.0157", "steering_offset.module_4_rad=0.0262"});
  b.single("sensor_latency/small", s, "encoders and gyro 0.02 s late", 211,
           {"sensor_latency.delay_s=0.02"});
  b.single("sensor_latency/large", s, "encoders and gyro 0.06 s late", 212,
           {"sensor_latency.delay_s=0.06"});
  b.single("actuator_lag/small", s, "wheel and steering drives lag by 0.03 s", 213,
           {"actuator_lag.time_constant_s=0.03"});
  b.single("actuator_lag/large", s, "wheel and steering drives lag by 0.08 s", 214,
           {"actuator_lag.time_constant_s=0.08"});
  b.single("steering_lag/small", s, "steering drives alone lag by 0.03 s", 215,
           {"steering_lag.time_constant_s=0.03"});
  b.single("steering_lag/large", s, "steering drives alone lag by 0.08 s", 216,
           {"steering_lag.time_constant_s=0.08"});
  b.single("steering_rate_limit/small", s, "steering rates clamped to 2 rad/s (model: 6)", 217,
           {"steering_rate_limit.radps=2.0"});
  b.single("steering_rate_limit/large", s, "steering rates clamped to 1 rad/s (model: 6)", 218,
           {"steering_rate_limit.radps=1.0"});
  b.single("accel_limit/small", s,
           "controller limits acceleration to 0.6 m/s^2, 2 rad/s^2; the model states only the "
           "steering limit",
           219, {}, ModelLimits::kSteeringOnly);
  b.single("accel_limit/large", s,
           "controller limits acceleration to 0.3 m/s^2, 1 rad/s^2; the model states only the "
           "steering limit",
           220, {"accel_limit.linear_mps2=0.3", "accel_limit.angular_radps2=1.0"},
           ModelLimits::kSteeringOnly);
  b.single("slip/small", s, "acceleration slip, gain 0.001 per rad/s^2", 221,
           {"slip.gain_per_radps2=0.001"});
  b.single("slip/large", s, "acceleration slip, gain 0.003 per rad/s^2", 222,
           {"slip.gain_per_radps2=0.003"});

  // Pairs.
  b.add("docent/pair/gyro_bias+wheel_radius", d, CaseKind::kPair,
        "gyro bias +0.004 rad/s and left wheel 1.2 % larger", 151,
        {"gyro_bias.bias_rad_s=0.004", "wheel_radius.left_scale=1.012"});
  b.add("docent/pair/track_width+actuator_lag", d, CaseKind::kPair,
        "track 3 % wider and wheel drives lagging by 0.06 s", 152,
        {"track_width.scale=1.03", "actuator_lag.time_constant_s=0.06"});
  b.add("docent/pair/gyro_scale+sensor_latency", d, CaseKind::kPair,
        "gyro scale 1.012 and encoders and gyro 0.04 s late", 153,
        {"gyro_scale.scale=1.012", "sensor_latency.delay_s=0.04"});
  b.add("swpc4/pair/steering_offset+sensor_latency", s, CaseKind::kPair,
        "steering offsets (0.7, -0.5, 0.9, 0.6) degrees and sensors 0.04 s late", 251,
        {"steering_offset.module_1_rad=0.012", "steering_offset.module_2_rad=-0.008",
         "steering_offset.module_3_rad=0.015", "steering_offset.module_4_rad=0.01",
         "sensor_latency.delay_s=0.04"});
  b.add("swpc4/pair/wheel_radius+accel_limit", s, CaseKind::kPair,
        "modules 2 and 4 wheels +1.5 % and -1.2 %, acceleration limited to 0.3 m/s^2, 1 rad/s^2 "
        "(model states only the steering limit)",
        252,
        {"wheel_radius.module_2_scale=1.015", "wheel_radius.module_4_scale=0.988",
         "accel_limit.linear_mps2=0.3", "accel_limit.angular_radps2=1.0"},
        ModelLimits::kSteeringOnly);
  b.add("swpc4/pair/caster_offset+gyro_bias", s, CaseKind::kPair,
        "caster offsets of modules 1 and 4 x1.2 and x0.85, gyro bias +0.004 rad/s", 253,
        {"caster_offset.module_1_scale=1.2", "caster_offset.module_4_scale=0.85",
         "gyro_bias.bias_rad_s=0.004"});

  // Outside the library: a correct workflow names none of its effects.
  const auto outside = [&](Robot robot, const std::string& name, const std::string& description,
                           std::uint64_t seed, std::initializer_list<const char*> settings) {
    b.add(robot_name(robot) + "/outside/" + name, robot, CaseKind::kOutside, description, seed, {},
          ModelLimits::kAll, settings);
  };
  outside(d, "floor_drift", "motion-capture frame drifts 1.9 mm/s against the floor", 301,
          {"floor_drift.vx_mps=0.0015", "floor_drift.vy_mps=0.0012"});
  outside(d, "dropped_counts", "an encoder loses 5-50 counts at once, every 4 s on average", 302,
          {"dropped_counts.interval_s=4"});
  outside(d, "eccentric_wheel", "right wheel eccentric, radius r (1 + 0.015 cos psi)", 303,
          {"eccentric_wheel.wheel=2", "eccentric_wheel.amplitude=0.015"});
  outside(d, "gyro_drift", "gyro bias drifts from -0.004 to +0.004 rad/s over the run", 304,
          {"gyro_drift.rad_s=0.004"});
  outside(s, "floor_drift", "motion-capture frame drifts 2.5 mm/s against the floor", 401,
          {"floor_drift.vx_mps=-0.002", "floor_drift.vy_mps=0.0015"});
  outside(s, "dropped_counts", "a wheel encoder loses 5-50 counts at once, every 4 s on average",
          402, {"dropped_counts.interval_s=4"});
  outside(s, "eccentric_wheel", "module 2 wheel eccentric, radius r (1 + 0.015 cos psi)", 403,
          {"eccentric_wheel.wheel=2", "eccentric_wheel.amplitude=0.015"});
  outside(s, "gyro_drift", "gyro bias drifts from -0.004 to +0.004 rad/s over the run", 404,
          {"gyro_drift.rad_s=0.004"});
  return b.cases;
}

}  // namespace

std::string case_kind_name(CaseKind kind) {
  switch (kind) {
    case CaseKind::kClean: return "clean";
    case CaseKind::kSingle: return "single";
    case CaseKind::kPair: return "pair";
    case CaseKind::kOutside: return "outside";
  }
  return "unknown";
}

const std::vector<BatteryCase>& battery() {
  static const std::vector<BatteryCase> cases = build();
  return cases;
}

std::vector<BatteryCase> battery_subset() {
  static constexpr const char* kIds[] = {"docent/clean/1",
                                         "swpc4/clean/1",
                                         "docent/gyro_bias/large",
                                         "swpc4/steering_offset/large",
                                         "docent/actuator_lag/large",
                                         "swpc4/accel_limit/large",
                                         "docent/pair/track_width+actuator_lag",
                                         "swpc4/outside/floor_drift"};
  std::vector<BatteryCase> subset;
  for (const char* id : kIds) {
    const BatteryCase* c = find_case(id);
    if (c == nullptr) throw std::logic_error(std::string("battery subset: no case ") + id);
    subset.push_back(*c);
  }
  return subset;
}

const BatteryCase* find_case(const std::string& id) {
  for (const BatteryCase& c : battery()) {
    if (c.id == id) return &c;
  }
  return nullptr;
}

}  // namespace swivel::independent
