// SPDX-License-Identifier: Apache-2.0
#pragma once
// What a plugin receives when it is configured (off the real-time loop).

#include <yaml-cpp/yaml.h>

#include <string>

#include "swivel/robot_model.hpp"

namespace swivel {

struct PluginContext {
  YAML::Node params;                  ///< the plugin's `params:` mapping (may be null)
  std::string config_file;            ///< file `params` came from, for messages
  std::string params_path;            ///< key path of `params`, e.g. "localization.params"
  std::string config_dir;             ///< base directory for relative paths in params
  const RobotModel* robot = nullptr;  ///< nominal robot model (never null when configured)
  double period_s = 0.001;            ///< loop period
};

}  // namespace swivel
