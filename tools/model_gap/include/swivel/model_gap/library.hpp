#pragma once
// The candidates the workflow fits, per question, and how each one's parameters are fitted
// and written into a robot model. What the effects do to the world is defined once, in the
// simulator's effect library (plugins/hardware/sim/include/swivel/sim/effects.hpp); the
// robot's own limits are the model's `limits:` section. This file adds only how to fit them.
//
//   sensor to pose     gyro_bias, gyro_scale, wheel_radius, track_width | caster_offset,
//                      steering_offset, sensor_latency, slip
//   command to motion  actuator_lag, steering_lag, accel_limit (limits.linear_acceleration_mps2,
//                      .angular_acceleration_radps2), steering_rate_limit
//                      (limits.steering_rate_radps)
//
// Slip belongs to sensor to pose: it is the relation between how far a wheel turned (the
// encoder) and how far its contact point moved (motion capture), whatever the command was.
// Limits are fitted as their inverse (1 / limit): zero is "no limit", and the fit moves
// smoothly from there.

#include <span>
#include <string>
#include <vector>

#include "swivel/model_gap/channels.hpp"
#include "swivel/model_gap/fit.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::model_gap {

struct Candidate {
  enum class Target { kEffect, kLimits };
  std::string name;  ///< effect name, or accel_limit / steering_rate_limit
  Question question = Question::kSensorToPose;
  Target target = Target::kEffect;
  std::vector<std::string> keys;  ///< effect parameter keys, or `limits:` keys
  std::vector<ParamSpec> params;  ///< in fit units; name = "<name>.<key>"
  std::vector<double> identity;   ///< fit units: the nominal model's own value
  std::vector<char> inverse;      ///< fitted as 1 / value

  /// Writes fit-unit values into `model` (effects or limits).
  void apply(RobotModel& model, std::span<const double> theta) const;
  /// Reported value of parameter i and its standard deviation, from fit units.
  [[nodiscard]] double value(std::size_t i, double fit) const;
  [[nodiscard]] double sigma(std::size_t i, double fit, double fit_sigma) const;
};

/// What the run shows of the robot's motion, for the limits' starting values.
struct MotionPeaks {
  double accel_mps2 = 0.0;           ///< high percentile of the measured body acceleration
  double angular_accel_radps2 = 0.0;
  double steer_rate_radps = 0.0;     ///< high percentile of the measured steering rates
};

/// Every candidate of `question` that applies to the model's drivetrain.
std::vector<Candidate> candidate_library(const RobotModel& nominal, Question question,
                                         const MotionPeaks& peaks);

}  // namespace swivel::model_gap
