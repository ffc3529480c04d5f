#include "swivel/model_gap/library.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {
namespace {

// Typical magnitude of each effect parameter: the fit works in units of it, and it sets the
// finite-difference step.
double typical_magnitude(const std::string& effect) {
  if (effect == "gyro_bias") return 0.005;        // rad/s
  if (effect == "steering_offset") return 0.02;   // rad
  if (effect == "slip") return 0.002;             // per rad/s^2
  if (effect == "actuator_lag" || effect == "steering_lag") return 0.05;  // s
  if (effect == "sensor_latency") return 0.02;    // s
  if (effect == "caster_offset") return 0.1;      // factor
  return 0.01;  // scale factors: gyro_scale, wheel_radius, track_width
}

bool in_question(const std::string& effect, Question q) {
  static const char* const kSensor[] = {"gyro_bias",       "gyro_scale",     "wheel_radius",
                                        "track_width",     "caster_offset",  "steering_offset",
                                        "sensor_latency",  "slip"};
  static const char* const kCommand[] = {"actuator_lag", "steering_lag"};
  if (q == Question::kSensorToPose) {
    return std::any_of(std::begin(kSensor), std::end(kSensor), [&](const char* e) { return effect == e; });
  }
  return std::any_of(std::begin(kCommand), std::end(kCommand), [&](const char* e) { return effect == e; });
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
  if (stated->has_value()) {
    s.initial = identity;
  } else {
    s.initial = peak > 0.0 ? 1.0 / (0.9 * peak) : scale;
  }
  c.keys.push_back(key);
  c.params.push_back(s);
  c.identity.push_back(identity);
  c.inverse.push_back(1);
}

}  // namespace

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
  if (!inverse[i]) return fit;
  return fit > 1e-12 ? 1.0 / fit : std::numeric_limits<double>::infinity();
}

double Candidate::sigma(std::size_t i, double fit, double fit_sigma) const {
  if (!inverse[i]) return fit_sigma;
  return fit > 1e-12 ? fit_sigma / (fit * fit) : std::numeric_limits<double>::infinity();
}

std::vector<Candidate> candidate_library(const RobotModel& nominal, Question question,
                                         const MotionPeaks& peaks) {
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
      if (have != nominal.effects.end() && have->second.count(p.key) != 0U) {
        identity = have->second.at(p.key);
      }
      s.initial = identity;
      // A lag or delay is flat in its parameter near zero (shorter than an integration
      // step): start such fits inside the range, at a typical value.
      if (p.identity <= p.min && identity <= p.min) s.initial = p.min + s.scale;
      s.lower = p.min;
      s.upper = p.max;
      if (e.name == "sensor_latency") s.upper = std::min(s.upper, 0.25);
      c.keys.push_back(p.key);
      c.params.push_back(s);
      c.identity.push_back(identity);
      c.inverse.push_back(0);
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
