// SPDX-License-Identifier: Apache-2.0
#pragma once
// The candidates the workflow fits, per question, and how each one's parameters are fitted
// and written into a robot model. What the effects do to the world is defined once, in the
// simulator's effect library (plugins/hardware/sim/include/swivel/sim/effects.hpp); the
// robot's own limits are the model's `limits:` section. This file adds only how to fit them.
//
//   sensor to pose     gyro_bias, gyro_scale, wheel_radius, track_width | caster_offset,
//                      module_layout, steering_offset, sensor_latency, slip
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
  /// Per parameter, in model units: what the replay cannot resolve, added in quadrature to
  /// the statistical uncertainty (0: nothing). A lag trades against when in its row the log
  /// caught each command (a row period over sqrt 12); a limit against the replay's sub-step
  /// (0.3 % of the limit).
  std::vector<double> resolution;
  /// Per parameter, as a fraction of the fitted value, added like `resolution`. A sensor
  /// latency: 0.5 %, from when the anchors' local path shape came from the nominal
  /// (undelayed) dead reckoning and left fitted delays short; kept, as a caster robot's
  /// latency is still biased by its tyres' scrub (GAP.md section 9).
  std::vector<double> relative_resolution;
  /// Whether the effect is named only once further from the model's own values than its
  /// resolution allows, besides its significance. Not a lag's: a row over sqrt 12 bounds
  /// when one command step arrived, and those instants are independent from step to step and
  /// measured as noise (CommandReplay::timing_variance), so the lag's own likelihood ratio
  /// already holds them (1440 clean runs' lags stayed below 4 sigma; one later at 5.45 was a
  /// 1.7 ms lag carried by the nuisance beside it, and failed the other tests). The
  /// resolution still widens its sigma. A limit's sub-step acts on every ramp alike.
  bool named_only_when_resolved = true;

  /// Writes fit-unit values into `model` (effects or limits).
  void apply(RobotModel& model, std::span<const double> theta) const;
  /// Reported value of parameter i and its standard deviation, from fit units.
  [[nodiscard]] double value(std::size_t i, double fit) const;
  [[nodiscard]] double sigma(std::size_t i, double fit, double fit_sigma) const;
  /// Resolution of parameter i in fit units at fit value `fit` (0: none).
  [[nodiscard]] double fit_resolution(std::size_t i, double fit) const;
};

/// What the run shows of the robot's motion, for the limits' starting values.
struct MotionPeaks {
  double accel_mps2 = 0.0;  ///< high percentile of the measured body acceleration
  double angular_accel_radps2 = 0.0;
  double steer_rate_radps = 0.0;  ///< high percentile of the measured steering rates
};

/// The question a candidate belongs to, by name (e.g. "slip" -> sensor to pose,
/// "accel_limit" -> command to motion). @throws std::invalid_argument for an unknown name.
Question question_of(const std::string& candidate);

/// Every candidate of `question` that applies to the model's drivetrain; `row_period_s` is
/// the run's (for the lags' resolution).
std::vector<Candidate> candidate_library(const RobotModel& nominal, Question question,
                                         const MotionPeaks& peaks, double row_period_s = 0.01);

}  // namespace swivel::model_gap
