// SPDX-License-Identifier: Apache-2.0
#pragma once
// The command-to-motion replay: the logged commands driven through the robot's controller
// (the nominal geometry it knows, the limits of the model under test) into the simulator's
// world (the model's actuators and effects, noise off), compared window by window with the
// measured wheel and steering encoders.
//
// The question is how the robot's actuators answered its commands; how the encoders' motion
// moved the robot is the sensor-to-pose question's. So the replayed body does not move
// (SimOptions::move_body), which makes this replay cheap enough to fit, except on a caster
// robot whose servos yield (below): there the body's motion is what turns the casters. The
// whole robot is replayed for the report's path (path()).
//
// Logged commands are samples of a signal that may change between rows. A row's command is
// taken to hold from halfway to the row before to halfway to the row after: for a signal
// that ramps this is as good as interpolating, and a step (a new setpoint) is as likely to
// have come early as late in its row, where interpolation would start every step half a row
// early and the robot's limiter would carry that lead through its whole ramp. The replay
// takes the commands `command_delay_s` late, a timing nuisance fitted beside the effects;
// what remains of each step's unknown instant is noise, which timing_variance() measures.
// The robot's limiter is replayed in half-millisecond steps, each through every logged
// command's own span within it, so that a ramp starts where its command changed and the
// replay's timing moves smoothly with the fitted delay (a limiter fed one mean command per
// step starts each ramp at the start of its step, and the delay would sit on the flats
// between steps).
//
// A caster steers itself towards trailing its motion: the steering law phi_dot =
// (n . v_s) / d - w pulls a trailing caster back at |v_s| / d (25 /s at 0.5 m/s on a 2 cm
// offset) and pushes a leading one away as fast. Where a caster leads (swinging through a
// reversal), which way and how fast it turns hangs on its angle to within less than the
// encoder count the log resolves, so such windows are not compared. Elsewhere the replayed
// caster runs free, as the robot's did, and trailing pulls both back into line.
//
// A caster robot's steering servos yield to their tyres (ActuatorNuisance::steering_yield_rad;
// sim::CasterForces): a servo whose reference runs ahead of what its tyre lets the caster do
// (a controller that steers by a geometry or angles the robot does not have) winds up until it
// drags the tyre across the floor, and the caster stays behind by the servo error whose torque
// matches the tyre's friction; where the motion turns the caster back, or the robot stops and
// starts, it lets go. Rigid servos would turn the replay's casters exactly as commanded, and
// the steering and wheel channels would blame that on an effect. With a yield, the casters
// and body move by the balance of the tyres', servos' and body's forces at every sub-step.
//
// Channels, per window: replay.wheel_<l|r|i>_rad (wheel rotation), replay.steer_<i>_rad
// (steering rotation, swpc).

#include <vector>

#include "swivel/model_gap/channels.hpp"
#include "swivel/model_gap/run_data.hpp"
#include "swivel/model_gap/sensor_replay.hpp"
#include "swivel/model_gap/windows.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/sim/world.hpp"

namespace swivel::model_gap {

/// What the command replay fits beside the effects.
struct ActuatorNuisance {
  /// The commands taken this late, s.
  double command_delay_s = 0.0;
  /// Servo error at which a caster's tyre gives way (swpc), rad; 0: rigid servos.
  double steering_yield_rad = 0.0;
};

class CommandReplay {
 public:
  /// Largest command delay a fit may try, either way, as a multiple of the row period.
  static constexpr double kMaxCommandDelayRows = 1.0;

  /// Uses the windows and motion-capture anchors of `sensors` (same run), and its nominal
  /// dead-reckoned path `path` (one pose per row) for the casters' motion.
  CommandReplay(const RobotModel& nominal, const RunData& run, const SensorReplay& sensors,
                const std::vector<Pose2>& path);

  /// Per window: false where a caster swung through a reversal (not compared).
  [[nodiscard]] const std::vector<char>& compared() const { return compared_; }

  [[nodiscard]] const std::vector<ChannelInfo>& channels() const { return channels_; }
  [[nodiscard]] std::size_t window_count() const { return windows_->size(); }
  /// The run's mean row period, s.
  [[nodiscard]] double row_period_s() const { return row_period_s_; }

  /// Measured minus predicted change of every channel over every window (channel-major),
  /// for the robot `model` with the actuators' nuisance `actuators`. False when the
  /// simulation fails.
  bool residuals(const RobotModel& model, const ActuatorNuisance& actuators,
                 std::vector<double>& out,
                 std::size_t window_limit = static_cast<std::size_t>(-1)) const;

  /// Variance each window's residual gets (channel-major) from not knowing when within its
  /// row each change of the commands came, a uniform instant. With d_k the change of row k's
  /// turn when every command is taken a row later: (sum d_k)^2 / 12 for a shift common to
  /// the window's changes, plus sum d_k^2 / 12 for each row's own. The common part alone
  /// vanishes in a window that ends turning as fast as it began (a turn slowing, then a
  /// translation starting), though each change in it came at an instant of its own.
  [[nodiscard]] std::vector<double> timing_variance(const RobotModel& model,
                                                    const ActuatorNuisance& actuators) const;

  /// The replayed robot's true pose at every row, from the run's start pose.
  void path(const RobotModel& model, const ActuatorNuisance& actuators,
            std::vector<Pose2>& out) const;

 private:
  struct Track {
    std::vector<Pose2> pose;  // unwrapped heading (with the body moving)
    std::vector<std::vector<double>> wheel;
    std::vector<std::vector<double>> steer;  // per row: turn in the row
  };
  // The world's options: noise off, from the run's start and its first steering angles.
  [[nodiscard]] sim::SimOptions world_options(const sim::PlantParams& plant,
                                              const ActuatorNuisance& actuators,
                                              bool move_body) const;
  bool simulate(const RobotModel& model, const ActuatorNuisance& actuators, std::size_t end_row,
                bool move_body, Track& track) const;

  RobotModel nominal_;
  const RunData* run_ = nullptr;
  const SensorReplay* sensors_ = nullptr;
  const std::vector<Window>* windows_ = nullptr;
  bool swpc_ = false;
  std::size_t modules_ = 2;
  double row_period_s_ = 0.01;
  std::vector<char> compared_;
  std::vector<char> reseat_;  ///< per row: casters re-seated on the log's angles after it
  std::vector<ChannelInfo> channels_;
  mutable Track track_;
};

}  // namespace swivel::model_gap
