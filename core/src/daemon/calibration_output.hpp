// SPDX-License-Identifier: Apache-2.0
#pragma once
// Where the daemon writes a calibrated robot model. Under systemd the configuration folder
// is read-only (ProtectSystem=full) and the unit's StateDirectory= (/var/lib/swivel) is the
// place for what the service makes; systemd passes it as $STATE_DIRECTORY. Run by hand, the
// model goes next to the nominal one. A model that cannot be written anywhere is not lost:
// the caller keeps it and reports every folder tried.

#include <ctime>
#include <string>
#include <vector>

#include "swivel/robot_model.hpp"

namespace swivel::daemon {

/// "swpc4.calibrated-20240131T120000.yaml" in `dir` (the folder of `model_path` when `dir` is
/// empty), with "-2", "-3", ... before ".yaml" when that file exists already (never an
/// existing file's name).
std::string calibrated_model_path(const std::string& model_path, std::time_t now,
                                  const std::string& dir = "");

/// The folders to try, in order: the first entry of $STATE_DIRECTORY (systemd gives a
/// ':'-separated list) when set, then the folder of `model_path`.
std::vector<std::string> calibration_output_dirs(const std::string& model_path);

struct SavedModel {
  std::string path;   ///< the file written; empty when none could be
  std::string error;  ///< when none could be: each folder tried and why it failed
};

/// Writes `model` (its source_file set to the file written) to the first folder of
/// calibration_output_dirs() that takes it. Never throws for a failed write.
SavedModel save_calibrated_model(RobotModel model, const std::string& model_path, std::time_t now);

}  // namespace swivel::daemon
