// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/library.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string_view>

#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {
namespace {

// What the replay resolves of a fitted limit, relative: it applies the limiter per sub-step
// (5 ms on a four-caster robot) where the robot does per control cycle, which places a
// ramp's end anywhere within a sub-step: h / sqrt(12) over a ramp of about half a second
// is 0.3 % of its duration, and of the limit (on the independent battery the fitted limits
// are 0.0-0.6 % off).
constexpr double kLimitResolution = 0.003;
// Candidate::relative_resolution of a sensor latency.
constexpr double kLatencyResolution = 0.005;

// Typical magnitude of each effect parameter: the fit works in units of it, and it sets the
// finite-difference step.
double typical_magnitude(const std::string& effect) {
  if (effect == "gyro_bias") return 0.005;                                // rad/s
  if (effect == "steering_offset") return 0.02;                           // rad
  if (effect == "slip") return 0.002;                                     // per rad/s^2
  if (effect == "actuator_lag" || effect == "steering_lag") return 0.05;  // s
  if (effect == "sensor_latency") return 0.02;                            // s
  if (effect == "caster_offset") return 0.1;                              // factor
  return 0.01;  // scale factors: gyro_scale, wheel_radius, track_width, track_scrub,
                // module_layout
}

constexpr std::array<std::string_view, 10> kSensorEffects = {
    "gyro_bias",     "gyro_scale",    "wheel_radius",    "track_width",    "track_scrub",
    "caster_offset", "module_layout", "steering_offset", "sensor_latency", "slip"};
constexpr std::array<std::string_view, 2> kCommandEffects = {"actuator_lag", "steering_lag"};

bool in_question(const std::string& effect, Question q) {
  if (q == Question::kSensorToPose)
    return std::ranges::find(kSensorEffects, effect) != kSensorEffects.end();
  return std::ranges::find(kCommandEffects, effect) != kCommandEffects.end();
}

std::optional<double>* limit_field(MotionLimits& limits, const std::string& key) {
  if (key == "linear_acceleration_mps2") return &limits.linear_acceleration_mps2;
  if (key == "angular_acceleration_radps2") return &limits.angular_acceleration_radps2;
  if (key == "steering_rate_radps") return &limits.steering_rate_radps;
  return nullptr;
}

// A limit candidate: fitted as u = 1 / limit from the model's stated limit (identity) or,
// when it states none, from "no limit" (identity 0) starting just below the run's peak.
void add_limit(Candidate& c, RobotModel model, const std::string& key, double peak, double scale) {
  const std::optional<double>* stated = limit_field(model.limits, key);
  ParamSpec s;
  s.name = c.name + "." + key;
  s.scale = scale;
  s.lower = 0.0;
  s.upper = 100.0;
  const double identity = stated->has_value() ? 1.0 / **stated : 0.0;
  s.anchor = identity;
  // A fit started at a limit the run never reaches cannot move (nothing depends on it):
  // start where it would act, a little below the run's peak, unless the stated limit does.
  const bool stated_acts = stated->has_value() && !(peak > 0.0 && **stated > peak);
  if (stated_acts) {
    s.initial = identity;
  } else {
    s.initial = peak > 0.0 ? 1.0 / (0.9 * peak) : stated->has_value() ? identity : scale;
  }
  c.keys.push_back(key);
  c.params.push_back(s);
  c.identity.push_back(identity);
  c.inverse.push_back(1);
  c.resolution.push_back(0.0);  // relative: see Candidate::sigma
  c.relative_resolution.push_back(0.0);
}

}  // namespace

Question question_of(const std::string& candidate) {
  if (in_question(candidate, Question::kSensorToPose)) return Question::kSensorToPose;
  if (in_question(candidate, Question::kCommandToMotion) || candidate == "accel_limit" ||
      candidate == "steering_rate_limit") {
    return Question::kCommandToMotion;
  }
  throw std::invalid_argument("unknown model-gap candidate '" + candidate + "'");
}

void Candidate::apply(RobotModel& model, std::span<const double> theta) const {
  if (target == Target::kEffect) {
    auto& values = model.effects[name];
    for (std::size_t i = 0; i < keys.size(); ++i) values[keys[i]] = theta[i];
    return;
  }
  for (std::size_t i = 0; i < keys.size(); ++i) {
    std::optional<double>* field = limit_field(model.limits, keys[i]);
    if (field == nullptr) continue;
    const double u = theta[i];
    if (u > 1e-9) {
      *field = 1.0 / u;
    } else {
      field->reset();
    }
  }
}

double Candidate::value(std::size_t i, double fit) const {
  if (inverse[i] == 0) return fit;
  return fit > 1e-12 ? 1.0 / fit : std::numeric_limits<double>::infinity();
}

double Candidate::fit_resolution(std::size_t i, double fit) const {
  // A relative resolution of the limit is the same relative resolution of 1 / limit.
  return inverse[i] != 0 ? kLimitResolution * std::abs(fit)
                         : std::hypot(resolution[i], relative_resolution[i] * std::abs(fit));
}

double Candidate::sigma(std::size_t i, double fit, double fit_sigma) const {
  if (inverse[i] == 0) return std::hypot(fit_sigma, fit_resolution(i, fit));
  if (!(fit > 1e-12)) return std::numeric_limits<double>::infinity();
  const double limit = 1.0 / fit;
  return std::hypot(fit_sigma / (fit * fit), kLimitResolution * limit);
}

std::vector<Candidate> candidate_library(const RobotModel& nominal, Question question,
                                         const MotionPeaks& peaks, double row_period_s) {
  std::vector<Candidate> out;
  for (const sim::EffectInfo& e : sim::effect_library(nominal)) {
    if (!in_question(e.name, question)) continue;
    Candidate c;
    c.name = e.name;
    c.question = question;
    const auto have = nominal.effects.find(e.name);
    for (const sim::EffectParamInfo& p : e.params) {
      ParamSpec s;
      s.name = e.name + "." + p.key;
      s.scale = typical_magnitude(e.name);
      // An effect the nominal model already carries is refitted from its own value.
      double identity = p.identity;
      if (have != nominal.effects.end() && have->second.contains(p.key)) {
        identity = have->second.at(p.key);
      }
      s.initial = identity;
      s.anchor = identity;
      // A lag or delay is flat in its parameter near zero (shorter than an integration
      // step): start such fits inside the range, at a typical value.
      if (p.identity <= p.min && identity <= p.min) s.initial = p.min + s.scale;
      s.lower = p.min;
      s.upper = p.max;
      if (e.name == "sensor_latency") s.upper = std::min(s.upper, 0.25);
      // A layout changes the turn rate through the spread of the module positions, quadratic
      // in its two scales, and a robot whose modules are centred on its reference point fixes
      // only that spread (GAP.md, "Combinations the run cannot fix").
      s.hold_when_unfixed = e.name == "module_layout";
      c.keys.push_back(p.key);
      c.params.push_back(s);
      c.identity.push_back(identity);
      c.inverse.push_back(0);
      const bool lag = e.name == "actuator_lag" || e.name == "steering_lag";
      c.resolution.push_back(lag ? row_period_s / std::sqrt(12.0) : 0.0);
      c.relative_resolution.push_back(e.name == "sensor_latency" ? kLatencyResolution : 0.0);
      c.named_only_when_resolved = !lag;
    }
    out.push_back(std::move(c));
  }
  if (question == Question::kCommandToMotion) {
    Candidate accel;
    accel.name = "accel_limit";
    accel.question = question;
    accel.target = Candidate::Target::kLimits;
    add_limit(accel, nominal, "linear_acceleration_mps2", peaks.accel_mps2, 1.0);
    add_limit(accel, nominal, "angular_acceleration_radps2", peaks.angular_accel_radps2, 0.5);
    out.push_back(std::move(accel));
    if (nominal.drivetrain == DrivetrainKind::kSwpc) {
      Candidate steer;
      steer.name = "steering_rate_limit";
      steer.question = question;
      steer.target = Candidate::Target::kLimits;
      add_limit(steer, nominal, "steering_rate_radps", peaks.steer_rate_radps, 0.2);
      out.push_back(std::move(steer));
    }
  }
  return out;
}

}  // namespace swivel::model_gap
