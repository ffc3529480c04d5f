#pragma once
// Measured and predicted channels of a run on one common time base. Plain data: the
// replay fills the predictions, the locating and fitting code reads residuals from them.

#include <cstddef>
#include <string>
#include <vector>

namespace swivel::model_gap {

/// Which question a channel answers (DESIGN.md "Model-gap workflow").
enum class Question {
  kSensorToPose,     ///< dead reckoning from encoders and gyro, compared with motion capture
  kCommandToSensor,  ///< commands re-simulated, compared with encoders, steering and gyro
  kCommandToPose,    ///< commands re-simulated, compared with motion capture
};

/// Name used in reports: "sensor_to_pose", "command_to_sensor", "command_to_pose".
const char* question_name(Question q);

/// What a channel measures; decides the regressors that describe its residual.
enum class ChannelKind {
  kPosition,     ///< world-frame coordinate, m
  kHeading,      ///< world-frame yaw, rad (residual wrapped to (-pi, pi])
  kWheelAngle,   ///< cumulative wheel angle, rad
  kSteerAngle,   ///< measured steering angle, rad (residual wrapped)
  kYawRate,      ///< gyro, rad/s
};

struct ChannelInfo {
  std::string name;  ///< e.g. "dead_reckoning.x_m", "simulation.wheel_l_rad"
  std::string unit;  ///< "m", "rad", "rad/s"
  Question question = Question::kCommandToSensor;
  ChannelKind kind = ChannelKind::kWheelAngle;
};

/// Samples of several channels; values[c][k] is channel c at sample k (NaN where absent,
/// e.g. no motion-capture sample).
struct ChannelSet {
  std::vector<ChannelInfo> info;
  std::vector<std::vector<double>> values;

  [[nodiscard]] std::size_t channel_count() const { return info.size(); }
  /// Index of the channel named `name`, or channel_count() when there is none.
  [[nodiscard]] std::size_t find(const std::string& name) const;
};

/// measured - predicted for one channel and sample; angles wrapped, NaN when either is.
double residual_at(const ChannelInfo& info, double measured, double predicted);

/// Residual of every channel: measured - predicted (same shape as the inputs).
/// @throws std::invalid_argument when the two sets do not have the same channels and length.
std::vector<std::vector<double>> residuals(const ChannelSet& measured,
                                           const ChannelSet& predicted);

}  // namespace swivel::model_gap
