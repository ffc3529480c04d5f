// SPDX-License-Identifier: Apache-2.0
#pragma once
// The sensor-to-pose replay: dead reckoning from the logged encoders, steering angles and
// gyro through the drivetrain's kinematics library and the E/G odometry of the raw_eg
// plugin, with a robot's parameters (nominal plus effects), compared window by window with
// motion capture. Independent of the commands: what the robot was told to do does not
// enter.
//
// Channels, per window, in the robot frame at the window's start:
//   dead_reckoning.dx_m, .dy_m   displacement (encoders, heading from the gyro)
//   dead_reckoning.dyaw_gyro_rad heading change from the gyro
//   dead_reckoning.dyaw_encoders_rad heading change from the encoders (and steering) alone

#include <vector>

#include "swivel/model_gap/channels.hpp"
#include "swivel/model_gap/run_data.hpp"
#include "swivel/model_gap/windows.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {

class SensorReplay {
 public:
  /// Longest sensor latency a fit may try: the windows end this long before the run does.
  static constexpr double kMaxLatencyS = 0.25;

  /// @throws std::invalid_argument when the run does not fit the model (drivetrain, module
  /// count), is shorter than 10 rows, or has no motion capture.
  SensorReplay(const RobotModel& nominal, const RunData& run, double window_s);

  [[nodiscard]] const std::vector<ChannelInfo>& channels() const { return channels_; }
  [[nodiscard]] const std::vector<Window>& windows() const { return windows_; }
  [[nodiscard]] const WindowMotion& motion() const { return motion_; }
  /// Motion capture at each window's ends (noise averaged, see anchor()).
  [[nodiscard]] const std::vector<Pose2>& anchors_start() const { return anchor_a_; }
  [[nodiscard]] const std::vector<Pose2>& anchors_end() const { return anchor_b_; }
  /// Start pose: motion capture averaged while the robot stands at the start (up to 1 s).
  [[nodiscard]] const Pose2& start_pose() const { return start_; }

  /// Measured minus predicted change of every channel over every window, channel-major
  /// (out[c * windows + w]), for a robot with parameters `plant`; only the first
  /// `window_limit` windows are replayed (the rest are NaN). False when the dead reckoning
  /// fails (degenerate kinematics or non-finite values).
  bool residuals(const sim::PlantParams& plant, std::vector<double>& out,
                 std::size_t window_limit = static_cast<std::size_t>(-1)) const;

  /// The dead-reckoned path, one pose per row (unwrapped heading), from start_pose(),
  /// with the sensor latency taken out (the pose at row k is the one for time t_k).
  void path(const sim::PlantParams& plant, std::vector<Pose2>& out) const;

 private:
  bool integrate(const sim::PlantParams& plant, std::size_t end_row) const;
  Pose2 pose_at(double t_s) const;
  double encoder_yaw_at(double t_s) const;

  const RunData* run_ = nullptr;
  bool swpc_ = false;
  std::size_t modules_ = 2;
  Pose2 start_;
  std::vector<std::vector<double>> slip_h_;  // 1/2 w|w| of the smoothed wheel rates
  std::vector<ChannelInfo> channels_;
  std::vector<Window> windows_;
  WindowMotion motion_;
  std::vector<Pose2> anchor_a_;
  std::vector<Pose2> anchor_b_;
  // Scratch of the last integration.
  mutable std::vector<Pose2> track_;
  mutable std::vector<double> encoder_yaw_;
};

/// Start pose of a run: motion capture averaged while the robot stands still at the start
/// (up to 1 s), so that one noisy sample does not tilt every replayed path.
/// @throws std::invalid_argument when the run has no motion capture at all.
Pose2 run_start_pose(const RunData& run);

/// Checks that `run` fits `model` (drivetrain, module count) and has at least 10 rows.
/// @throws std::invalid_argument naming both files.
void check_run_fits_model(const RobotModel& model, const RunData& run);

}  // namespace swivel::model_gap
