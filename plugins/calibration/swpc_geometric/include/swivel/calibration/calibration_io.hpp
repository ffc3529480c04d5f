// SPDX-License-Identifier: Apache-2.0
#pragma once
// Recorded data in, robot model out: turns calibration run logs (swivel/run_log.hpp) into
// the calibration's input, and a calibration result into a calibrated robot model. Not
// real-time safe (allocates, throws); used by the offline tools and off the daemon's loop.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "swivel/calibration/swpc_calibration.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/run_log.hpp"

namespace swivel::calibration {

/// Which module a calibration log locked, and the measured steering angle it was locked at
/// when the log (or the user) declares one.
struct LockSpec {
  std::size_t locked_module = 0;  ///< 0-based
  std::optional<double> declared_steer_rad;
};

/// The comment line every calibration log carries, e.g.
/// "calibration: locked_module 2, locked_steer_rad 0.785398, yaw_rate_radps 0.3"
/// (module 1-based, as on the command line).
std::string calibration_comment(const LockSpec& lock, double yaw_rate_radps);

/// The lock declared by a log's `# calibration:` comment, or nullopt when it has none.
/// @throws std::invalid_argument naming the log when the line is malformed.
std::optional<LockSpec> lock_from_comments(const RunLog& log);

/// A declared locked angle may differ from the locked module's steering encoder by at most
/// this much before the log is rejected: a larger gap means the wrong module or angle.
inline constexpr double kMaxDeclaredLockMismatchRad = 0.017453292519943295;  // 1 deg

/// One locked run from a log: the rows that carry a motion-capture sample, with the encoder
/// readings of the same rows (the daemon and the simulator log both on one clock). The
/// locked angle is the mean of the locked module's steering encoder over the run: the
/// measurement a real procedure has; a declared angle only cross-checks it.
/// @throws std::invalid_argument naming the log: not an swpc log, module out of range,
///   fewer than 2 motion-capture rows, or a declared angle off the encoder by more than
///   kMaxDeclaredLockMismatchRad.
LockedRun locked_run_from_log(const RunLog& log, const LockSpec& lock);

/// All runs of a procedure; the module count comes from the logs, which must agree.
/// @throws std::invalid_argument as locked_run_from_log, or for logs of different robots.
CalibrationInput calibration_input_from_logs(const std::vector<RunLog>& logs,
                                             const std::vector<LockSpec>& locks);

/// Calibration options for a robot's encoders: the steering encoder's quantization
/// (uniform, step / sqrt(12)) as the 1-sigma of a measured locked angle.
CalibrationOptions calibration_options_for(const RobotModel& model);

/// `nominal` with every module's parameters replaced by the calibrated ones.
/// @pre result.ok() and result.modules.size() == nominal.modules.size().
RobotModel calibrated_model(const RobotModel& nominal, const CalibrationResult& result);

}  // namespace swivel::calibration
