// SPDX-License-Identifier: Apache-2.0
#pragma once
// The sensor-to-pose replay: dead reckoning from the logged encoders, steering angles and
// gyro through the drivetrain's kinematics library and the E/G odometry of the raw_eg
// plugin, with a robot's parameters (nominal plus effects), compared window by window with
// motion capture. Independent of the commands: what the robot was told to do does not
// enter.
//
// Channels, per window, in the robot frame at the window's start:
//   dead_reckoning.dx_m, .dy_m   displacement (encoders, heading from the gyro; from the
//                                encoders when the run has no gyro)
//   dead_reckoning.dyaw_gyro_rad heading change from the gyro (only when the run has one)
//   dead_reckoning.dyaw_encoders_rad heading change from the encoders (and steering) alone
//
// Motion capture tracks a rigid body that is never mounted exactly on the robot's reference
// point and axis, and a hand-synchronised log has its own clock offset. These are nuisances,
// fitted with every candidate and never named as robot effects (TruthNuisance):
//   truth.yaw_offset_rad   the tracked body's heading minus the robot's
//   truth.lever_x_m, _y_m  the tracked body's origin in the robot frame
//   truth.time_offset_s    how late the motion capture's time stamps are against the
//                          encoders' (either sign); fitted only when the run does not declare
//                          a shared clock (`# truth_clock: shared`), since in this question it
//                          cannot be told from a sensor latency; the offset at the run's
//                          middle
//   truth.clock_rate       how much faster the motion capture's clock runs than the encoders'
//                          (s/s): a log synchronised by hand at its start and end carries both
//                          pick errors as an offset that changes linearly over the run. It
//                          shows where the speed changes (the offset differs between the start
//                          and the end) and scales all motion alike (a mocap second that is
//                          longer covers more of it), so a common wheel-radius scale is fixed
//                          only by the accelerations. Fitted with the offset, except where the
//                          log declares the clocks run at one rate (`# truth_clock: same_rate`)
// A run whose truth is the robot's own reference frame (`# truth_frame: robot`, a simulator's)
// fits neither the yaw offset nor the lever arm.
//
// Windows in which the casters scrubbed are not compared: a caster steered at the rate limit
// (the model's stated one, or the fastest the run steers where that is lower or none is
// stated) and the casters disagreed about the body's motion (the forward kinematics'
// residual) 1.5 times as much as in the run's median window, or they disagreed 4 times as
// much whatever the steering (a caster that steers late). There the casters were off the
// angles their motion needs and a tyre scrubbed sideways, which the no-lateral-slip
// kinematics cannot hold. A robot whose casters keep rolling at the limit keeps those windows.

#include <span>
#include <vector>

#include "swivel/model_gap/channels.hpp"
#include "swivel/model_gap/fit.hpp"
#include "swivel/model_gap/run_data.hpp"
#include "swivel/model_gap/windows.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {

/// Where the tracked body sits on the robot, and the motion capture's clock offset.
struct TruthNuisance {
  double yaw_offset_rad = 0.0;
  double lever_x_m = 0.0;
  double lever_y_m = 0.0;
  double time_offset_s = 0.0;
  double clock_rate = 0.0;  ///< the offset grows by this much per second of the run
  /// The gyro's readings (samples at the rows' times) stand for the rate this much later
  /// between rows: summed by the trapezoid rule, a rate whose ramps start on rows turns the
  /// heading late (the limiter's ramps start on the controller's ticks). Within half a row.
  double gyro_shift_s = 0.0;

  /// The tracked body's pose in the robot frame.
  [[nodiscard]] Pose2 body() const { return Pose2{lever_x_m, lever_y_m, yaw_offset_rad}; }
};

class SensorReplay {
 public:
  /// Longest sensor latency a fit may try: the windows end this long before the run does.
  static constexpr double kMaxLatencyS = 0.25;
  /// Largest motion-capture clock offset fitted, either sign (hand-synchronised logs are
  /// seen up to about a third of a second out).
  static constexpr double kMaxTimeOffsetS = 0.5;
  /// Largest motion-capture clock rate difference fitted, either sign (OptiOdom's runs: the
  /// two clocks' spans differ from their median ratio by -0.55 to +0.29 %).
  static constexpr double kMaxClockRate = 0.01;

  /// @throws std::invalid_argument when the run does not fit the model (drivetrain, module
  /// count), is shorter than 10 rows, or has no motion capture.
  SensorReplay(const RobotModel& nominal, const RunData& run, double window_s);

  /// The nuisance parameters the question fits beside every candidate (TruthNuisance, in
  /// that order; the time offset only when the run's clocks are not declared shared).
  [[nodiscard]] const std::vector<ParamSpec>& nuisance() const { return nuisance_; }
  /// The run has a gyro: its heading drives the dead reckoning and it has its own channel.
  [[nodiscard]] bool uses_gyro() const { return gyro_; }
  /// The motion capture's clock offset is fitted (the run does not declare a shared clock).
  [[nodiscard]] bool fits_time_offset() const { return fit_time_offset_; }
  /// The motion capture's clock rate is fitted too (its clock may run at its own rate).
  [[nodiscard]] bool fits_clock_rate() const { return fit_clock_rate_; }
  /// The tracked body's offset on the robot is fitted (the run does not declare that its
  /// truth is the robot's frame).
  [[nodiscard]] bool fits_body_offset() const { return fit_body_offset_; }
  /// The nuisance values (nuisance() order) as a TruthNuisance; those not fitted are zero.
  [[nodiscard]] TruthNuisance truth(std::span<const double> values) const;

  [[nodiscard]] const std::vector<ChannelInfo>& channels() const { return channels_; }
  [[nodiscard]] const std::vector<Window>& windows() const { return windows_; }
  [[nodiscard]] const WindowMotion& motion() const { return motion_; }
  /// Motion capture at each window's ends (noise averaged along the nominal dead reckoning,
  /// see anchor()): the windows' own motion. residuals() averages along each replay's path.
  [[nodiscard]] const std::vector<Pose2>& anchors_start() const { return anchor_a_; }
  [[nodiscard]] const std::vector<Pose2>& anchors_end() const { return anchor_b_; }
  /// Per window: the casters scrubbed, held at a rate limit or steering late (see above);
  /// such windows are not compared.
  [[nodiscard]] const std::vector<char>& scrubbing() const { return scrubbing_; }
  /// Start pose: motion capture averaged while the robot stands at the start (up to 1 s).
  [[nodiscard]] const Pose2& start_pose() const { return start_; }

  /// Measured minus predicted change of every channel over every window, channel-major
  /// (out[c * windows + w]), for a robot with parameters `plant`; only the first
  /// `window_limit` windows are replayed (the rest are NaN). False when the dead reckoning
  /// fails (degenerate kinematics or non-finite values).
  bool residuals(const sim::PlantParams& plant, const TruthNuisance& truth,
                 std::vector<double>& out,
                 std::size_t window_limit = static_cast<std::size_t>(-1)) const;

  /// The dead-reckoned path, one pose per row (unwrapped heading), as the motion capture
  /// would see it: the robot started where the motion capture put it at rest, its path
  /// carried to the tracked body and shifted by the sensor latency and the clock offset (the
  /// pose at row k is comparable with the motion capture of row k).
  void path(const sim::PlantParams& plant, const TruthNuisance& truth,
            std::vector<Pose2>& out) const;

 private:
  bool integrate(const sim::PlantParams& plant, const Pose2& start, std::size_t end_row,
                 double gyro_shift_s) const;
  /// The gyro's mean rate over row k (t[k-1], t[k]], its readings standing for the rate
  /// `gyro_shift_s` later.
  [[nodiscard]] double gyro_mean(std::size_t k, double gyro_shift_s) const;
  Pose2 pose_at(double t_s) const;
  double encoder_yaw_at(double t_s) const;
  /// How much later than its row the encoders' time is that the motion capture of a row at
  /// t_s shows: the sensor delay less the motion capture's clock offset there.
  double shift_at(double sensor_delay_s, const TruthNuisance& truth, double t_s) const {
    return sensor_delay_s - truth.time_offset_s - truth.clock_rate * (t_s - clock_reference_s_);
  }

  /// shape_: the replayed path as the motion capture would show it (carried to the tracked
  /// body, at each row's time shifted as shift_at() says), in the rows the anchors of the
  /// first `windows` windows average over; NaN elsewhere.
  void track_shape(const sim::PlantParams& plant, const TruthNuisance& truth,
                   std::size_t windows) const;

  const RunData* run_ = nullptr;
  // The motion capture's noise is averaged into a window's end along the replay's own path
  // (anchor()): along the nominal one, a path the sensors show late would be the motion's
  // shape at the wrong instant, and a fitted latency came out up to 2 % short.
  mutable std::vector<Pose2> shape_;
  bool swpc_ = false;
  bool gyro_ = true;
  bool fit_time_offset_ = true;
  bool fit_clock_rate_ = true;
  double clock_reference_s_ = 0.0;  // the run's middle: where truth.time_offset_s applies
  bool fit_body_offset_ = true;
  std::size_t modules_ = 2;
  std::vector<ParamSpec> nuisance_;
  Pose2 start_;
  std::vector<std::vector<double>> slip_h_;  // 1/2 w|w| of the smoothed wheel rates
  std::vector<ChannelInfo> channels_;
  std::vector<Window> windows_;
  WindowMotion motion_;
  std::vector<Pose2> anchor_a_;
  std::vector<Pose2> anchor_b_;
  std::vector<char> scrubbing_;
  // Scratch of the last integration.
  mutable std::vector<Pose2> track_;
  mutable std::vector<double> encoder_yaw_;
};

/// Start pose of a run: motion capture averaged while the robot stands still at the start
/// (up to 1 s), so that one noisy sample does not tilt every replayed path.
/// @throws std::invalid_argument when the run has no motion capture at all.
Pose2 run_start_pose(const RunData& run);

/// Checks that `run` fits `model` (drivetrain, module count), has at least 10 rows, and a value
/// per row in every column. @throws std::invalid_argument naming the files or the column.
void check_run_fits_model(const RobotModel& model, const RunData& run);

}  // namespace swivel::model_gap
