// SPDX-License-Identifier: Apache-2.0
#pragma once
// Geometric kinematic calibration of a robot on N single-wheel powered casters
// (docs/methods.md §1): from motion capture and encoder data recorded while the robot turns about
// one locked module, twice per module at two locked steering angles, recover every module's
// steering-axis position (x, y), steering offset delta, caster offset d and wheel radius r.
//
// Conventions (the same as swivel_swpc_kinematics): robot frame x forward, y left; yaw
// counter-clockwise positive; heading u = (cos phi, sin phi); wheel contact c = p - d u;
// measured steering = true steering - delta. Plain maths: no threads, DDS or YAML. Not
// real-time safe (allocates); run it off the loop.

#include <cstddef>
#include <string>
#include <vector>

#include "swivel/robot_model.hpp"

namespace swivel::calibration {

/// Data of one rotation about a locked module. Sample k of every series is taken at t_s[k]:
/// motion capture and encoders are synchronised (resample before calling if they are not).
struct RunSeries {
  std::vector<double> t_s;      ///< strictly increasing, s
  std::vector<double> x_m;      ///< robot origin, world frame (motion capture)
  std::vector<double> y_m;      ///< robot origin, world frame (motion capture)
  std::vector<double> yaw_rad;  ///< robot heading, world frame, counter-clockwise positive
  /// Cumulative wheel encoder angle per module: wheel_angle_rad[module][sample], rad.
  std::vector<std::vector<double>> wheel_angle_rad;
  /// Measured steering angle per module, [module][sample], rad. Optional: empty, or one
  /// series per module (used only for the self-alignment and lock checks).
  std::vector<std::vector<double>> steer_angle_rad;
};

/// One rotation of the robot about module `locked_module`'s wheel contact point.
struct LockedRun {
  std::size_t locked_module = 0;       ///< 0-based module index
  double locked_steer_meas_rad = 0.0;  ///< measured (encoder) steering of the locked module
  RunSeries data;
};

/// Everything the calibration needs: exactly two runs (two locked steering angles) per
/// module, in any order; the first run of a module is "P1" and the second "P2".
struct CalibrationInput {
  std::size_t module_count = 0;  ///< N >= 2
  std::vector<LockedRun> runs;
};

/// Thresholds of the quality verdict and the noise model of the steering encoder.
struct CalibrationOptions {
  double min_rotation_rad = 0.5235987755982988;  ///< 30 deg of robot rotation per run
  double max_pivot_residual_rms_m = 0.002;       ///< RMS misfit of the pivot fit
  /// Locked angles must differ by at least this, and by at most 2 pi minus this: eq. (1)
  /// divides by sin(dphi / 2).
  double min_locked_angle_separation_rad = 0.3490658503988659;  ///< 20 deg
  double min_wheel_rotation_rad = 0.5;        ///< every free wheel must turn at least this
  double max_locked_wheel_motion_rad = 0.02;  ///< locked wheel encoder range (lock held)
  double max_locked_steer_motion_rad = 0.02;  ///< locked steering encoder range
  double max_free_steer_motion_rad = 0.1745329251994330;  ///< 10 deg: free casters settled
  double max_r_relative_spread = 0.02;   ///< (max - min) / mean of one module's r estimates
  std::size_t min_samples = 10;          ///< per run
  double steer_encoder_sigma_rad = 0.0;  ///< 1-sigma of a measured locked angle
};

/// One check of the verdict, e.g. {"enough_rotation", false, "module 2 run 1: 12.0 deg ..."}.
struct QualityCheck {
  std::string name;
  bool passed = true;
  std::string detail;  ///< what was found; names the module and run when it fails
};

/// Pass/fail per check. The calibration returns parameters only when every check passes.
struct QualityVerdict {
  std::vector<QualityCheck> checks;

  [[nodiscard]] bool passed() const;
  /// One line per check: "PASS name: detail" / "FAIL name: detail".
  [[nodiscard]] std::string text() const;
  /// The details of the failed checks joined by "; " (empty when all passed).
  [[nodiscard]] std::string failure_reason() const;
};

/// 1-sigma uncertainty of each parameter (first-order propagation of the fit residuals,
/// combined with the spread of the repeated wheel-radius estimates).
struct SwpcModuleSigma {
  double x_m = 0.0;
  double y_m = 0.0;
  double steering_offset_rad = 0.0;
  double caster_offset_m = 0.0;
  double wheel_radius_m = 0.0;
};

/// The pivot (centre of rotation, robot frame) of one run.
struct PivotFit {
  double x_m = 0.0;
  double y_m = 0.0;
  double sigma_m = 0.0;         ///< 1-sigma per coordinate (the fit's covariance is isotropic)
  double residual_rms_m = 0.0;  ///< RMS misfit of the motion-capture positions
  double rotation_rad = 0.0;    ///< robot rotation over the run (signed)
};

struct ModuleCalibration {
  SwpcModuleParams params;  ///< calibrated values
  SwpcModuleSigma sigma;    ///< their 1-sigma uncertainties
  PivotFit pivot1;          ///< first locked angle
  PivotFit pivot2;          ///< second locked angle
  /// The 2(N-1) estimates of r from the runs where this module was free, m.
  std::vector<double> wheel_radius_estimates_m;
};

/// Either calibrated modules (ok()) or a refusal whose reason() says why.
struct CalibrationResult {
  QualityVerdict verdict;
  std::vector<ModuleCalibration> modules;  ///< empty when refused

  [[nodiscard]] bool ok() const { return !modules.empty() && verdict.passed(); }
  [[nodiscard]] std::string reason() const { return verdict.failure_reason(); }
};

/// Centre of rotation of a rigid motion, in the robot frame: the point P with
/// W = t_k + R(yaw_k) P for one world point W at every sample, by linear least squares
/// over all samples (closed form). Requires at least two distinct headings.
PivotFit fit_pivot(const std::vector<double>& x_m, const std::vector<double>& y_m,
                   const std::vector<double>& yaw_rad);

/// Steering axis, caster offset and steering offset of one module from its two pivots and
/// measured locked angles: eq. (1) d = |P1P2| / (2 sin(dphi/2)) with dphi = phi2m - phi1m
/// wrapped to (0, 2 pi); eq. (2)-(3) S = P1 + d * rot((pi - dphi)/2) (P2 - P1)/|P1P2|; and
/// delta = angle(S -> P1) - pi - phi1m wrapped to (-pi, pi].
/// @pre dphi is not a multiple of 2 pi and P1 != P2.
struct AxisGeometry {
  double x_m = 0.0;
  double y_m = 0.0;
  double caster_offset_m = 0.0;
  double steering_offset_rad = 0.0;
};
AxisGeometry steering_axis_from_pivots(double p1_x_m, double p1_y_m, double p2_x_m, double p2_y_m,
                                       double phi1_meas_rad, double phi2_meas_rad);

/// Runs the whole calibration. Never throws on bad data: it refuses with a reason instead.
CalibrationResult calibrate(const CalibrationInput& input, const CalibrationOptions& options = {});

/// Wraps an angle to (-pi, pi].
double wrap_pi(double angle_rad);

}  // namespace swivel::calibration
