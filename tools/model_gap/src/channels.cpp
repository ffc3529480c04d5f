// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/channels.hpp"

namespace swivel::model_gap {

const char* question_name(Question q) {
  return q == Question::kSensorToPose ? "sensor_to_pose" : "command_to_motion";
}

const char* question_title(Question q) {
  return q == Question::kSensorToPose ? "sensor to pose" : "command to motion";
}

}  // namespace swivel::model_gap
