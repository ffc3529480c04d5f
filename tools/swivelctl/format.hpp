// SPDX-License-Identifier: Apache-2.0
#pragma once
// How swivelctl prints samples: one line each, or one JSON object per line.

#include <nlohmann/json.hpp>
#include <string>

#include "swivel.h"

namespace swivel::ctl {

const char* mode_name(swivel_msg_LoopMode mode);

nlohmann::json to_json(const swivel_msg_RobotState& s);
nlohmann::json to_json(const swivel_msg_ModuleStates& s);
nlohmann::json to_json(const swivel_msg_Diagnostics& s);
nlohmann::json to_json(const swivel_msg_CalibrationResult& s);

std::string to_line(const swivel_msg_RobotState& s);
std::string to_line(const swivel_msg_ModuleStates& s);
std::string to_line(const swivel_msg_Diagnostics& s);
std::string to_line(const swivel_msg_CalibrationResult& s);

}  // namespace swivel::ctl
