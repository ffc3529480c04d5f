// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/odometry_stage.hpp"

#include "swivel/rt/finite.hpp"

namespace swivel::rt {
namespace {

// What is published: a non-finite covariance goes out as none (robot_localization and Nav2
// reject NaN), while the fault says why.
PoseEstimate publishable(PoseEstimate e) noexcept {
  if (!finite_covariance(e)) {
    e.covariance = {};
    e.has_covariance = false;
  }
  return e;
}

}  // namespace

OdometryStage::OdometryStage(const OdometryCheckOptions& check, const TwistWindowOptions& window)
    : monitor_(check), twist_window_(window) {}

OdometryOutcome OdometryStage::update(double now_s, const HardwareReadStage& read, bool reading_ok,
                                      const StateSnapshot& published, double published_s,
                                      Drivetrain& drivetrain, Localization& localization,
                                      PluginGuard& guard, LoopEvents& events) noexcept {
  const HardwareState& current = read.current();
  if (!reading_ok && read.has_previous() && !reading_gap_.active()) {
    // Readings stopped: the odometry follows the controlled stop until they resume.
    reading_gap_.begin(published.estimate, published.odometry_twist,
                       published.has_twist_covariance ? &published.twist_covariance : nullptr,
                       published_s);
  }
  const bool resuming = reading_ok && reading_gap_.active();

  // The twist window goes first: its forward kinematics calls leave the drivetrain's module
  // states to the cycle's own call.
  OdometryOutcome out;
  OdometryIncrement& odometry = out.odometry;
  const char* thrown = nullptr;
  if (reading_ok) {
    if (!read.has_previous() || resuming) twist_window_.reset();  // no fit across a gap
    twist_window_.push(current);
  }
  if (reading_ok && read.has_previous()) {
    // A refusal here is no fault: the cycle's own forward() below decides that.
    out.twist_ok = guard([&] { return twist_window_.estimate(drivetrain, twist_estimate_); },
                         thrown) == Status::kOk;
    if (guard([&] { return drivetrain.forward(read.previous(), current, odometry); }, thrown) !=
        Status::kOk) {
      events.raise(FaultCode::kDrivetrainError, now_s,
                   thrown != nullptr ? thrown : drivetrain.last_error());
      // An encoder jump must not stay in the window once the fault is cleared.
      twist_window_.reset();
      out.twist_ok = false;
    } else if (resuming && end_reading_gap(localization, odometry, now_s, guard, events)) {
      // The motion over the gap went into the handed-over covariance, not into the pose.
    } else if (guard([&] { return localization.update(odometry, current); }, thrown) !=
               Status::kOk) {
      events.raise(FaultCode::kLocalizationError, now_s,
                   thrown != nullptr ? thrown : localization.last_error());
    } else if (!finite(localization.estimate().pose)) {
      events.raise(FaultCode::kLocalizationError, now_s, "non-finite pose estimate");
    } else if (!finite_covariance(localization.estimate())) {
      events.raise(FaultCode::kLocalizationError, now_s, "non-finite pose covariance");
    }
    if (odometry.valid) check(odometry, current, now_s, events);
  }
  if (resuming && reading_gap_.active()) {
    // Nothing measured over the gap (the hardware was paused, or the drivetrain refused the
    // increment): the dead-reckoned pose is all there is.
    (void)end_reading_gap(localization, OdometryIncrement{}, now_s, guard, events);
  }
  return out;
}

// Readings resumed after a gap: the localization takes the dead-reckoned pose with the
// covariance widened by what the encoders measured over the gap (`measured`), so that the
// pose does not jump. False when it refuses: it then continues from its own estimate.
bool OdometryStage::end_reading_gap(Localization& localization, const OdometryIncrement& measured,
                                    double now_s, PluginGuard& guard, LoopEvents& events) noexcept {
  const PoseEstimate handed = reading_gap_.resume(measured, now_s);
  const char* thrown = nullptr;
  if (guard([&] { return localization.hand_over(handed); }, thrown) != Status::kOk) {
    events.log(LogLevel::kWarn, LogCode::kMessage, now_s,
               "readings resumed: the localization refused the dead-reckoned pose", 0.0, 0.0, 0.0,
               0.0, thrown != nullptr ? thrown : localization.last_error());
    return false;
  }
  events.log(LogLevel::kInfo, LogCode::kMessage, now_s,
             "readings resumed: pose kept, covariance widened by the gap's error (m, rad)",
             reading_gap_.last_position_error_m(), reading_gap_.last_heading_error_rad());
  return true;
}

// A frozen or slipping encoder: the odometry keeps disagreeing with the gyro, or (redundant
// drivetrains) with itself.
void OdometryStage::check(const OdometryIncrement& odometry, const HardwareState& reading,
                          double now_s, LoopEvents& events) noexcept {
  switch (monitor_.update(odometry, reading.gyro_valid, reading.gyro_wz_radps)) {
    case OdometryMonitor::Verdict::kConsistent: return;
    case OdometryMonitor::Verdict::kGyroDisagrees:
      events.raise(FaultCode::kOdometryInconsistent, now_s,
                   "encoder yaw rate disagrees with the gyro", monitor_.yaw_difference_radps(),
                   monitor_.gyro_limit_radps());
      return;
    case OdometryMonitor::Verdict::kResidualHigh:
      events.raise(FaultCode::kOdometryInconsistent, now_s,
                   "drivetrain odometry residual above its limit", monitor_.residual_mps(),
                   monitor_.options().residual_limit_mps);
      return;
  }
}

void OdometryStage::publish(const OdometryOutcome& outcome, const Localization& localization,
                            StateSnapshot& state) noexcept {
  state.estimate =
      reading_gap_.active() ? reading_gap_.estimate() : publishable(localization.estimate());
  if (outcome.twist_ok) {
    state.odometry_twist = twist_estimate_.twist;
    state.twist_covariance = twist_estimate_.covariance;
    state.has_twist_covariance = twist_estimate_.has_covariance;
    state.wheel_rate_radps = twist_estimate_.wheel_rate_radps;
    state.steer_rate_radps = twist_estimate_.steer_rate_radps;
    state.has_joint_rates = true;
    reading_gap_.forget_twist();
  } else if (reading_gap_.has_twist()) {
    state.odometry_twist = reading_gap_.twist();
    state.twist_covariance = reading_gap_.twist_covariance();
    state.has_twist_covariance = reading_gap_.has_twist_covariance();
    state.has_joint_rates = false;
  } else {
    state.odometry_twist = outcome.odometry.valid ? outcome.odometry.twist : Twist2{};
    state.twist_covariance = {};
    state.has_twist_covariance = false;
    state.has_joint_rates = false;
  }
  state.odometry_residual = outcome.odometry.valid ? outcome.odometry.residual : 0.0;
}

void OdometryStage::set_resolutions(double wheel_resolution_rad,
                                    double steer_resolution_rad) noexcept {
  if (!twist_window_.set_resolutions(wheel_resolution_rad, steer_resolution_rad)) {
    (void)twist_window_.set_resolutions(0.0, 0.0);  // unknown: no covariance
  }
  twist_window_.reset();
}

}  // namespace swivel::rt
