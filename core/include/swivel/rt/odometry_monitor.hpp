// SPDX-License-Identifier: Apache-2.0
#pragma once
// Sustained-disagreement check on the odometry (docs/faults.md, "Frozen encoder"). Two
// independent views of the motion are compared every cycle, each low-pass filtered so that
// encoder quantization (a 1 kHz rate from angle differences is noisy; its error telescopes
// and averages out) and a single bad cycle do not trip it:
//  - the yaw rate of the forward kinematics against the gyro (any drivetrain, while the gyro
//    is valid): a frozen wheel on a differential robot driving straight reads as a turn the
//    gyro does not see;
//  - the drivetrain's least-squares residual (drivetrains with redundant sensors, e.g. SWPC):
//    one frozen wheel of four cannot be explained by any rigid-body twist.
// A check trips when its filtered value stays above its limit for persistence_s. Plain
// maths on the loop thread: every method is real-time safe.

#include <cmath>

#include "swivel/types.hpp"

namespace swivel::rt {

/// Limits of the odometry consistency check (LoopOptions::odometry_check). The defaults and
/// the data behind them are in docs/faults.md.
struct OdometryCheckOptions {
  bool enabled = true;
  /// |filtered (encoder yaw rate - gyro yaw rate)| above this plus
  /// gyro_disagreement_fraction x |filtered gyro rate| is a disagreement, rad/s.
  double gyro_disagreement_radps = 0.2;
  /// Part of the disagreement allowed in proportion to the turn rate (slip while spinning).
  double gyro_disagreement_fraction = 0.1;
  /// Filtered drivetrain residual (OdometryIncrement::residual, m/s) above this is one.
  double residual_limit_mps = 0.04;
  /// Time constant of the first-order low-pass on both signals, s.
  double filter_time_constant_s = 0.05;
  /// How long a filtered value must stay above its limit before the check trips, s.
  double persistence_s = 0.2;
};

class OdometryMonitor {
 public:
  enum class Verdict : unsigned char { kConsistent, kGyroDisagrees, kResidualHigh };

  OdometryMonitor() noexcept = default;
  explicit OdometryMonitor(const OdometryCheckOptions& options) noexcept : options_(options) {}

  /// Real-time safe. Feeds one valid odometry increment and the cycle's gyro reading.
  /// Returns which check is tripped (kConsistent while none is).
  Verdict update(const OdometryIncrement& odometry, bool gyro_valid,
                 double gyro_wz_radps) noexcept {
    if (!options_.enabled || !odometry.valid || !(odometry.dt_s > 0.0)) return Verdict::kConsistent;
    const double dt_s = odometry.dt_s;
    const double alpha = dt_s / (options_.filter_time_constant_s + dt_s);
    if (gyro_valid) {
      yaw_difference_radps_ +=
          alpha * (odometry.twist.wz_radps - gyro_wz_radps - yaw_difference_radps_);
      gyro_rate_radps_ += alpha * (std::abs(gyro_wz_radps) - gyro_rate_radps_);
      gyro_above_s_ =
          std::abs(yaw_difference_radps_) > gyro_limit_radps() ? gyro_above_s_ + dt_s : 0.0;
    } else {
      // Nothing to compare with: start afresh when the gyro returns.
      yaw_difference_radps_ = 0.0;
      gyro_rate_radps_ = 0.0;
      gyro_above_s_ = 0.0;
    }
    residual_mps_ += alpha * (odometry.residual - residual_mps_);
    residual_above_s_ =
        residual_mps_ > options_.residual_limit_mps ? residual_above_s_ + dt_s : 0.0;

    if (gyro_above_s_ >= options_.persistence_s) return Verdict::kGyroDisagrees;
    if (residual_above_s_ >= options_.persistence_s) return Verdict::kResidualHigh;
    return Verdict::kConsistent;
  }

  /// Filtered encoder-minus-gyro yaw rate, rad/s.
  [[nodiscard]] double yaw_difference_radps() const noexcept { return yaw_difference_radps_; }
  /// The yaw-rate disagreement allowed now, rad/s.
  [[nodiscard]] double gyro_limit_radps() const noexcept {
    return options_.gyro_disagreement_radps +
           options_.gyro_disagreement_fraction * gyro_rate_radps_;
  }
  /// Filtered drivetrain residual, m/s.
  [[nodiscard]] double residual_mps() const noexcept { return residual_mps_; }
  [[nodiscard]] const OdometryCheckOptions& options() const noexcept { return options_; }

  /// Real-time safe. True when every limit is finite and positive (constructor callers
  /// validate with it off the loop).
  [[nodiscard]] static bool valid(const OdometryCheckOptions& o) noexcept {
    auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
    return positive(o.gyro_disagreement_radps) && positive(o.residual_limit_mps) &&
           std::isfinite(o.gyro_disagreement_fraction) && o.gyro_disagreement_fraction >= 0.0 &&
           positive(o.filter_time_constant_s) && positive(o.persistence_s);
  }

 private:
  OdometryCheckOptions options_{};
  double yaw_difference_radps_ = 0.0;
  double gyro_rate_radps_ = 0.0;  // filtered |gyro rate|
  double gyro_above_s_ = 0.0;
  double residual_mps_ = 0.0;
  double residual_above_s_ = 0.0;
};

}  // namespace swivel::rt
