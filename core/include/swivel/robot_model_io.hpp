// SPDX-License-Identifier: Apache-2.0
#pragma once
// Reading and writing robot models (YAML). Start-up code: throws ConfigError.

#include <string>

#include "swivel/robot_model.hpp"

namespace swivel {

/// Reads and validates a robot model file.
/// @throws ConfigError naming file, line, key and what was expected (unknown keys included).
RobotModel load_robot_model(const std::string& path);

/// Parses a robot model from YAML text; `source_name` is used in error messages.
/// @throws ConfigError as load_robot_model.
RobotModel parse_robot_model(const std::string& yaml_text, const std::string& source_name);

/// Writes a model in the same schema (round-trips through load_robot_model).
/// @throws std::runtime_error when the file cannot be written.
void save_robot_model(const RobotModel& model, const std::string& path);

/// The YAML text of a model.
std::string robot_model_to_yaml(const RobotModel& model);

}  // namespace swivel
