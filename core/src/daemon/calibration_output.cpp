// SPDX-License-Identifier: Apache-2.0
#include "calibration_output.hpp"

#include <cstdlib>
#include <exception>
#include <filesystem>

#include "swivel/robot_model_io.hpp"

namespace swivel::daemon {

namespace fs = std::filesystem;

std::string calibrated_model_path(const std::string& model_path, std::time_t now,
                                  const std::string& dir) {
  const fs::path original(model_path);
  std::string stem = original.filename().string();
  for (const char* extension : {".yaml", ".yml"}) {
    const std::string ext(extension);
    if (stem.size() > ext.size() && stem.compare(stem.size() - ext.size(), ext.size(), ext) == 0) {
      stem.resize(stem.size() - ext.size());
      break;
    }
  }
  std::tm local{};
  localtime_r(&now, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%S", &local);
  const std::string base = stem + ".calibrated-" + stamp;
  const fs::path folder = dir.empty() ? original.parent_path() : fs::path(dir);
  fs::path candidate = folder / (base + ".yaml");
  for (int k = 2; fs::exists(candidate); ++k) {
    candidate = folder / (base + "-" + std::to_string(k) + ".yaml");
  }
  return candidate.string();
}

std::vector<std::string> calibration_output_dirs(const std::string& model_path) {
  std::vector<std::string> dirs;
  if (const char* state = std::getenv("STATE_DIRECTORY"); state != nullptr && *state != '\0') {
    const std::string list(state);
    dirs.push_back(list.substr(0, list.find(':')));
  }
  std::string own = fs::path(model_path).parent_path().string();
  if (own.empty()) own = ".";
  if (dirs.empty() ||
      fs::path(dirs.front()).lexically_normal() != fs::path(own).lexically_normal()) {
    dirs.push_back(own);
  }
  return dirs;
}

SavedModel save_calibrated_model(RobotModel model, const std::string& model_path, std::time_t now) {
  SavedModel saved;
  for (const std::string& dir : calibration_output_dirs(model_path)) {
    const std::string path = calibrated_model_path(model_path, now, dir);
    try {
      model.source_file = path;
      save_robot_model(model, path);
      saved.path = path;
      saved.error.clear();
      return saved;
    } catch (const std::exception& e) {
      saved.error += (saved.error.empty() ? "" : "; ") + std::string(e.what());
    }
  }
  return saved;
}

}  // namespace swivel::daemon
