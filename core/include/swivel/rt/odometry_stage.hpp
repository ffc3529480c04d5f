// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's odometry and localization stage: from the cycle's reading to the published
// estimate and twist. The twist window fits the twist over the last readings; the drivetrain's
// forward kinematics gives the increment since the previous reading, which the active
// localization takes (its estimate checked finite) and the OdometryMonitor holds against the
// gyro and the drivetrain's residual. While readings are missing, ReadingGap dead-reckons with
// the twist the loop applies, and hands the localization the widened estimate when they resume.
// A refusal or a non-finite result is a latched fault: kDrivetrainError,
// kLocalizationError or kOdometryInconsistent.
//
// Loop thread only. Real-time safe: no allocation, no lock, no I/O; noexcept (plugins are
// called through the PluginGuard). The constructor is not: it checks the window's options.

#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/rt/hardware_read_stage.hpp"
#include "swivel/rt/loop_events.hpp"
#include "swivel/rt/odometry_monitor.hpp"
#include "swivel/rt/plugin_guard.hpp"
#include "swivel/rt/reading_gap.hpp"
#include "swivel/rt/state_snapshot.hpp"
#include "swivel/rt/twist_window.hpp"

namespace swivel::rt {

/// One cycle's odometry.
struct OdometryOutcome {
  OdometryIncrement odometry;  ///< since the previous reading (valid false when none)
  bool twist_ok = false;       ///< the twist window gave an estimate
};

class OdometryStage {
 public:
  /// @throws std::invalid_argument for window options TwistWindow refuses.
  OdometryStage(const OdometryCheckOptions& check, const TwistWindowOptions& window);

  /// The cycle's odometry from `read` (`reading_ok`: its current reading is usable).
  /// `published` is the previous cycle's snapshot and `published_s` its time: where a gap in
  /// the readings starts from.
  OdometryOutcome update(double now_s, const HardwareReadStage& read, bool reading_ok,
                         const StateSnapshot& published, double published_s, Drivetrain& drivetrain,
                         Localization& localization, PluginGuard& guard,
                         LoopEvents& events) noexcept;

  /// After the write: during a gap the pose moves on with the twist the loop applied.
  void advance(const Twist2& applied, double now_s) noexcept {
    if (reading_gap_.active()) reading_gap_.advance(applied, now_s);
  }

  /// The estimate, the twist with its covariance and joint rates, and the residual into the
  /// snapshot (the dead-reckoned ones during a gap).
  void publish(const OdometryOutcome& outcome, const Localization& localization,
               StateSnapshot& state) noexcept;

  /// A new robot model's encoder resolutions (0: unknown, no covariance); the window starts
  /// again from the next reading.
  void set_resolutions(double wheel_resolution_rad, double steer_resolution_rad) noexcept;

 private:
  bool end_reading_gap(Localization& localization, const OdometryIncrement& measured, double now_s,
                       PluginGuard& guard, LoopEvents& events) noexcept;
  void check(const OdometryIncrement& odometry, const HardwareState& reading, double now_s,
             LoopEvents& events) noexcept;

  OdometryMonitor monitor_;
  TwistWindow twist_window_;
  TwistEstimate twist_estimate_{};
  ReadingGap reading_gap_;  // odometry while readings are missing
};

}  // namespace swivel::rt
