// SPDX-License-Identifier: Apache-2.0
#pragma once
// Odometry through a gap in the hardware readings (a read fault, a non-finite reading). The
// encoders say nothing meanwhile, but the loop knows what it commands: the controlled stop.
// So, from the last measured twist and estimate:
//  - the published twist is the stop's model (the twist the loop applies each cycle). Each
//    axis's standard deviation is the last measured one plus the distance between the model
//    and the last measured twist: the robot is somewhere between braking as commanded and
//    still moving as it was (drives that miss the setpoints);
//  - the pose is dead-reckoned with that twist, and the standard deviations of position and
//    heading grow by the integral of the twist's (a speed error is systematic over a gap,
//    so the deviations add up rather than as a random walk);
//  - when readings resume, the drivetrain's increment over the whole gap (from the last
//    reading before it to the first after) is compared with the dead-reckoned motion. The
//    pose stays where dead reckoning put it, so that it does not jump, and the covariance is
//    widened by the square of the difference instead; the loop hands that estimate to the
//    localization (Localization::hand_over()) and the odometry continues from the new reading.
// Without a covariance at the gap's start (a localization that has none, encoders of unknown
// resolution) none is invented: the estimate and the twist stay without.
//
// Loop thread only; plain arithmetic: every method is real-time safe.

#include <array>

#include "swivel/types.hpp"

namespace swivel::rt {

class ReadingGap {
 public:
  /// The first cycle without a reading. `estimate` and `twist` are the last published ones
  /// (twist_covariance: the twist's row-major 3x3 over (vx, vy, wz), null when it has none),
  /// `since_s` the loop time of the cycle that published them.
  void begin(const PoseEstimate& estimate, const Twist2& twist,
             const std::array<double, 9>* twist_covariance, double since_s) noexcept;

  /// True from begin() until resume().
  [[nodiscard]] bool active() const noexcept { return active_; }

  /// Each cycle without a reading, once the loop knows the twist it applies (`model`): the
  /// pose moves on with the twist applied since the previous cycle, up to `now_s`, and the
  /// published twist becomes `model`.
  void advance(const Twist2& model, double now_s) noexcept;

  /// Readings resumed at `now_s`. `measured`: the drivetrain's increment from the last reading
  /// before the gap to this cycle's (valid false when there is none, e.g. after the hardware
  /// was paused). Returns the estimate to hand over: the dead-reckoned pose, its covariance
  /// widened by the difference to the measured motion. Ends the gap; the twist stays
  /// available (has_twist()) until the twist window has readings again.
  PoseEstimate resume(const OdometryIncrement& measured, double now_s) noexcept;

  /// The dead-reckoned estimate (while active).
  [[nodiscard]] const PoseEstimate& estimate() const noexcept { return estimate_; }

  /// True from begin() until forget_twist(): twist() and twist_covariance() stand in for the
  /// measured twist.
  [[nodiscard]] bool has_twist() const noexcept { return has_twist_; }
  [[nodiscard]] const Twist2& twist() const noexcept { return twist_; }
  [[nodiscard]] const std::array<double, 9>& twist_covariance() const noexcept {
    return twist_covariance_;
  }
  [[nodiscard]] bool has_twist_covariance() const noexcept { return has_twist_covariance_; }

  /// The twist is measured again.
  void forget_twist() noexcept { has_twist_ = false; }

  /// How far the measured motion over the last gap was from the dead-reckoned one: position,
  /// m, and heading, rad (0 until a gap has resumed with a measurement).
  [[nodiscard]] double last_position_error_m() const noexcept { return position_error_m_; }
  [[nodiscard]] double last_heading_error_rad() const noexcept { return heading_error_rad_; }

 private:
  void integrate(double now_s) noexcept;

  bool active_ = false;
  bool has_twist_ = false;
  PoseEstimate start_{};                    // the estimate at the gap's start
  PoseEstimate estimate_{};                 // dead-reckoned, with the grown covariance
  Twist2 measured_{};                       // the last measured twist
  std::array<double, 3> measured_sigma_{};  // its standard deviations (vx, vy, wz)
  Twist2 twist_{};                          // the model applied since last_s_
  std::array<double, 9> twist_covariance_{};
  bool has_twist_covariance_ = false;
  double last_s_ = 0.0;
  double position_sigma_m_ = 0.0;  // grown during the gap
  double heading_sigma_rad_ = 0.0;
  double position_error_m_ = 0.0;
  double heading_error_rad_ = 0.0;
};

}  // namespace swivel::rt
