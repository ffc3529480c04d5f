// SPDX-License-Identifier: Apache-2.0
#include "swivel/second/validation_set.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "planner.hpp"
#include "random.hpp"

namespace swivel::second {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

const std::vector<std::string>& swpc_designs() {
  static const std::vector<std::string> d = {"trike3", "cart4", "hex6"};
  return d;
}
const std::vector<std::string>& differential_designs() {
  static const std::vector<std::string> d = {"mini_diff", "wide_diff", "mid_diff"};
  return d;
}

// Effects of the library, per drivetrain, in the order the library cases cycle through.
const std::vector<std::pair<bool, std::string>>& effect_cycle() {
  static const std::vector<std::pair<bool, std::string>> c = {
      {false, "gyro_bias"},          {false, "gyro_scale"},     {false, "wheel_radius"},
      {false, "track_width"},        {false, "sensor_latency"}, {false, "actuator_lag"},
      {false, "accel_limit"},        {true, "gyro_bias"},       {true, "gyro_scale"},
      {true, "wheel_radius"},        {true, "caster_offset"},   {true, "steering_offset"},
      {true, "sensor_latency"},      {true, "actuator_lag"},    {true, "steering_lag"},
      {true, "steering_rate_limit"}, {true, "accel_limit"},
  };
  return c;
}

double sign(Stream& rng) { return rng.chance(0.5) ? 1.0 : -1.0; }

// What every case draws: robot, row rate, script, motion-capture mounting and timing, and
// the physics outside the library at clean values.
RunSpec base_spec(Stream& rng, const std::string& robot, std::uint64_t seed) {
  RunSpec s;
  s.design = robot;
  s.seed = seed;
  s.duration_s = kValidationDurationS;
  s.row_rate_hz = static_cast<double>(rng.integer(20, 100));
  s.script = static_cast<Script>(rng.integer(0, 3));
  s.truth.tyre_stiffness_per_load = rng.uniform(300.0, 600.0);
  s.truth.friction_coefficient = rng.uniform(0.6, 1.0);
  s.truth.steering_friction_nm = rng.uniform(0.005, 0.02);
  if (rng.chance(0.5)) {  // half of the runs: the tracked body off the robot's origin
    s.truth.mocap_latency_s = rng.uniform(0.0, 0.02);
    s.truth.marker_x_m = rng.uniform(-0.06, 0.06);
    s.truth.marker_y_m = rng.uniform(-0.06, 0.06);
    s.truth.marker_yaw_rad = rng.uniform(-3.0, 3.0) * kDeg;
  }
  return s;
}

std::string describe(const RunSpec& s) {
  char buf[160];
  std::snprintf(buf, sizeof buf,
                "%s, %.0f Hz rows, %s, mocap latency %.3f s marker (%.3f, %.3f) m %.2f deg",
                s.design.c_str(), s.row_rate_hz, script_name(s.script), s.truth.mocap_latency_s,
                s.truth.marker_x_m, s.truth.marker_y_m, s.truth.marker_yaw_rad / kDeg);
  return buf;
}

// One library effect at a size drawn between just clearly detectable and large.
void hide_effect(Stream& rng, RunSpec& s, const std::string& effect) {
  const Design d = design(s.design);
  const std::size_t n = d.wheel_count();
  Truth& t = s.truth;
  if (effect == "gyro_bias") {
    t.gyro_bias_rad_s = sign(rng) * rng.uniform(0.003, 0.008);
  } else if (effect == "gyro_scale") {
    t.gyro_scale = 1.0 + sign(rng) * rng.uniform(0.006, 0.025);
  } else if (effect == "wheel_radius") {
    t.wheel_radius_scale.assign(n, 1.0);
    const std::size_t changed = rng.chance(0.5) ? 1 : 2;
    for (std::size_t k = 0; k < changed; ++k) {
      t.wheel_radius_scale[static_cast<std::size_t>(rng.integer(0, static_cast<int>(n) - 1))] =
          1.0 + sign(rng) * rng.uniform(0.006, 0.02);
    }
  } else if (effect == "track_width") {
    t.track_width_scale = 1.0 + sign(rng) * rng.uniform(0.01, 0.05);
  } else if (effect == "caster_offset") {
    t.caster_offset_scale.assign(n, 1.0);
    const bool all = rng.chance(0.5);
    for (std::size_t i = 0; i < n; ++i) {
      if (all || i == 0) {
        t.caster_offset_scale[i] =
            rng.chance(0.5) ? rng.uniform(0.75, 0.9) : rng.uniform(1.1, 1.25);
      }
    }
  } else if (effect == "steering_offset") {
    t.steering_offset_rad.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i)
      t.steering_offset_rad[i] = sign(rng) * rng.uniform(0.4, 1.5) * kDeg;
  } else if (effect == "sensor_latency") {
    // Told apart from the motion capture's own delay only on a shared clock: none here.
    t.sensor_delay_s = rng.uniform(0.02, 0.08);
    t.mocap_latency_s = 0.0;
  } else if (effect == "actuator_lag") {
    t.actuator_lag_s = rng.uniform(0.03, 0.10);
  } else if (effect == "steering_lag") {
    t.steering_lag_s = rng.uniform(0.03, 0.10);
  } else if (effect == "steering_rate_limit") {
    t.steering_rate_limit_radps = d.steering_rate_limit_radps * rng.uniform(0.2, 0.4);
  } else if (effect == "accel_limit") {
    // The model states none; the robot's limits lie below the user's own ramps (which the
    // design's limits never bind), so that they act.
    s.model.accel_limits = false;
    const double share = d.drive == Drive::kSwpc ? Planner::kCasterEaseShare : 1.0;
    t.linear_accel_limit_mps2 = share * Planner::kEaseLinearMps2 * rng.uniform(0.4, 0.8);
    t.angular_accel_limit_radps2 = share * Planner::kEaseAngularRadps2 * rng.uniform(0.4, 0.8);
  }
}

}  // namespace

const char* case_kind_name(CaseKind kind) {
  switch (kind) {
    case CaseKind::kClean: return "clean";
    case CaseKind::kLibrary: return "library";
    case CaseKind::kOutside: return "outside";
  }
  return "?";
}

std::vector<std::string> library_case_effects() {
  std::vector<std::string> out;
  for (const auto& [swpc, effect] : effect_cycle()) {
    out.push_back(std::string(swpc ? "swpc/" : "differential/") + effect);
  }
  return out;
}

const SeedRanges* seed_ranges_named(std::string_view name) {
  if (name == "smoke") return &kSmokeSeeds;
  if (name == "validation") return &kValidationSeeds;
  if (name == "first-validation") return &kFirstValidationSeeds;
  if (name == "second-validation") return &kSecondValidationSeeds;
  if (name == "third-validation") return &kThirdValidationSeeds;
  if (name == "fourth-validation") return &kFourthValidationSeeds;
  if (name == "fifth-validation") return &kFifthValidationSeeds;
  if (name == "sixth-validation") return &kSixthValidationSeeds;
  if (name == "seventh-validation") return &kSeventhValidationSeeds;
  if (name == "eighth-validation") return &kEighthValidationSeeds;
  if (name == "ninth-validation") return &kNinthValidationSeeds;
  if (name == "tenth-validation") return &kTenthValidationSeeds;
  if (name == "eleventh-validation") return &kEleventhValidationSeeds;
  if (name == "twelfth-validation") return &kTwelfthValidationSeeds;
  if (name == "thirteenth-validation") return &kThirteenthValidationSeeds;
  if (name == "fourteenth-validation") return &kFourteenthValidationSeeds;
  if (name == "fifteenth-validation") return &kFifteenthValidationSeeds;
  return nullptr;
}

const std::vector<std::string>& seed_set_names() {
  static const std::vector<std::string> names = {"smoke",
                                                 "validation",
                                                 "first-validation",
                                                 "second-validation",
                                                 "third-validation",
                                                 "fourth-validation",
                                                 "fifth-validation",
                                                 "sixth-validation",
                                                 "seventh-validation",
                                                 "eighth-validation",
                                                 "ninth-validation",
                                                 "tenth-validation",
                                                 "eleventh-validation",
                                                 "twelfth-validation",
                                                 "thirteenth-validation",
                                                 "fourteenth-validation",
                                                 "fifteenth-validation"};
  return names;
}

ValidationCase clean_case(std::uint64_t first_seed, std::size_t index) {
  const std::uint64_t seed = first_seed + index;
  Stream rng(seed, kCaseStream);
  // Robots in turn, so that any count of cases spans them evenly.
  const std::vector<std::string> all = design_names();
  ValidationCase c;
  c.kind = CaseKind::kClean;
  c.spec = base_spec(rng, all[index % all.size()], seed);
  c.id = "clean/" + std::to_string(seed);
  c.description = describe(c.spec);
  c.expected = expected_effects(c.spec);
  return c;
}

ValidationCase library_case(std::uint64_t first_seed, std::size_t index) {
  const std::uint64_t seed = first_seed + index;
  Stream rng(seed, kCaseStream);
  const auto& [swpc, effect] = effect_cycle()[index % effect_cycle().size()];
  const auto& robots = swpc ? swpc_designs() : differential_designs();
  const std::string robot = robots[(index / effect_cycle().size()) % robots.size()];
  ValidationCase c;
  c.kind = CaseKind::kLibrary;
  c.spec = base_spec(rng, robot, seed);
  hide_effect(rng, c.spec, effect);
  c.id = effect + "/" + std::to_string(seed);
  c.expected = expected_effects(c.spec);
  c.description = describe(c.spec);
  return c;
}

ValidationCase outside_case(std::uint64_t first_seed, std::size_t index) {
  const std::uint64_t seed = first_seed + index;
  Stream rng(seed, kCaseStream);
  const std::vector<std::string> all = design_names();
  ValidationCase c;
  c.kind = CaseKind::kOutside;
  c.spec = base_spec(rng, all[index % all.size()], seed);
  // A slippery floor: friction below what turning and the user's ramps ask of it (0.06-0.12
  // m/s^2 of grip), soft tyres.
  c.spec.truth.friction_coefficient = rng.uniform(0.006, 0.012);
  c.spec.truth.tyre_stiffness_per_load = rng.uniform(8.0, 20.0);
  c.id = "slippery_floor/" + std::to_string(seed);
  c.expected = expected_effects(c.spec);
  c.description =
      describe(c.spec) + ", friction " + std::to_string(c.spec.truth.friction_coefficient);
  return c;
}

std::vector<ValidationCase> validation_set(const SeedRanges& seeds, std::size_t clean,
                                           std::size_t library, std::size_t outside) {
  std::vector<ValidationCase> out;
  for (std::size_t i = 0; i < clean; ++i) out.push_back(clean_case(seeds.clean, i));
  for (std::size_t i = 0; i < library; ++i) out.push_back(library_case(seeds.library, i));
  for (std::size_t i = 0; i < outside; ++i) out.push_back(outside_case(seeds.outside, i));
  return out;
}

}  // namespace swivel::second
