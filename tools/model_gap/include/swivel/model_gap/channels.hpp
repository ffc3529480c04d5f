// SPDX-License-Identifier: Apache-2.0
#pragma once
// The two questions the workflow answers and the channels that answer them. A channel is
// compared window by window (windows.hpp): the change of a measured quantity over a window
// against the change its replay predicts, so that noise integrated from the start of the
// run (dead reckoning, random wheel slip) does not pile up in the comparison.

#include <cstddef>
#include <string>
#include <vector>

namespace swivel::model_gap {

/// Which question a channel answers (tools/lab/GAP.md). The two are decided
/// separately: a disagreement in one never vetoes a finding in the other.
enum class Question {
  /// Geometry and sensors: the measured encoders, steering angles and gyro, dead-reckoned,
  /// against motion capture. Independent of how the robot responded to its commands.
  kSensorToPose,
  /// Actuators and the robot's own controller: the logged commands replayed through the
  /// simulator against the measured encoders, steering, gyro and motion capture.
  kCommandToMotion,
};

/// "sensor_to_pose", "command_to_motion" (report keys).
const char* question_name(Question q);
/// "sensor to pose", "command to motion" (report text).
const char* question_title(Question q);

/// What a channel measures over a window; decides its noise and misfit regressors.
enum class ChannelKind {
  kPosition,    ///< displacement along a robot axis at the window's start, m
  kHeading,     ///< heading change, rad
  kWheelAngle,  ///< wheel rotation, rad
  kSteerAngle,  ///< steering rotation, rad
};

struct ChannelInfo {
  std::string name;  ///< e.g. "dead_reckoning.dx_m", "replay.wheel_l_rad"
  std::string unit;  ///< "m", "rad"
  Question question = Question::kSensorToPose;
  ChannelKind kind = ChannelKind::kPosition;
  std::size_t module = 0;  ///< wheel or steering channels: the module (0-based)
};

}  // namespace swivel::model_gap
