// SPDX-License-Identifier: Apache-2.0
#include "kalman_localization.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/localization/eg_params.hpp"
#include "swivel/plugin/abi.hpp"

namespace swivel::plugins {
namespace {

using Matrix3 = localization::PoseEkf::Matrix3;

constexpr double kBig = 1e6;

}  // namespace

void KalmanLocalization::configure(const PluginContext& ctx) {
  if (ctx.robot == nullptr) throw ConfigError("kalman localization: no robot model");
  const RobotModel& robot = *ctx.robot;
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  KalmanConfig c;
  c.mode = params.choice_or("mode", "ekf", {"ekf", "lcakf"}) == "ekf" ? KalmanMode::kEkf
                                                                      : KalmanMode::kLcakf;
  c.eg = localization::read_eg_config(params, &robot);
  localization::EkfNoise& n = c.ekf;
  n.translation_m_per_sqrt_m =
      params.number_or("translation_noise_m_per_sqrt_m", n.translation_m_per_sqrt_m, 0.0, 10.0);
  n.rotation_rad_per_sqrt_rad =
      params.number_or("rotation_noise_rad_per_sqrt_rad", n.rotation_rad_per_sqrt_rad, 0.0, 10.0);
  n.yaw_rad_per_sqrt_m =
      params.number_or("yaw_noise_rad_per_sqrt_m", n.yaw_rad_per_sqrt_m, 0.0, 10.0);
  n.bias_walk_radps_per_sqrt_s =
      params.number_or("bias_random_walk_radps_per_sqrt_s", n.bias_walk_radps_per_sqrt_s, 0.0, 1.0);
  n.gyro_noise_radps =
      params.number_or("gyro_noise_radps", robot.sensors.gyro.noise_rad_s, 0.0, 10.0);
  n.fix_position_noise_m = params.number_or(
      "fix_position_noise_m", robot.sensors.motion_capture.position_noise_m, 1e-9, 100.0);
  n.fix_yaw_noise_rad =
      params.number_or("fix_yaw_noise_rad", robot.sensors.motion_capture.yaw_noise_rad, 1e-9, 10.0);
  c.use_pose_fixes = params.boolean_or("use_pose_fixes", true);
  c.initial_position_sigma_m = params.number_or("initial_position_sigma_m", 0.0, 0.0, 1e3);
  c.initial_yaw_sigma_rad = params.number_or("initial_yaw_sigma_rad", 0.0, 0.0, 10.0);
  c.initial_bias_sigma_radps =
      params.number_or("initial_bias_sigma_radps", c.initial_bias_sigma_radps, 0.0, 10.0);
  c.handover_position_sigma_m =
      params.number_or("handover_position_sigma_m", c.handover_position_sigma_m, 0.0, 1e3);
  c.handover_yaw_sigma_rad =
      params.number_or("handover_yaw_sigma_rad", c.handover_yaw_sigma_rad, 0.0, 10.0);
  c.lcakf.accel_mps2 = params.number_or("lcakf_accel_noise_mps2", c.lcakf.accel_mps2, 1e-9, 1e3);
  c.lcakf.position_m = params.number_or("lcakf_position_noise_m", c.lcakf.position_m, 1e-9, 1e3);
  params.finish();
  configure(c);
}

void KalmanLocalization::configure(const KalmanConfig& config) noexcept {
  config_ = config;
  ekf_.set_noise(config.ekf);
  lcakf_.set_noise(config.lcakf);
  eg_.set_config(config.eg);
  reset(PoseEstimate{});
}

void KalmanLocalization::reset(const PoseEstimate& initial) {
  const double pos_var = config_.initial_position_sigma_m * config_.initial_position_sigma_m;
  const double yaw_var = config_.initial_yaw_sigma_rad * config_.initial_yaw_sigma_rad;
  Matrix3 cov = Matrix3::Zero();
  cov.diagonal() << pos_var, pos_var, yaw_var;
  if (initial.has_covariance)
    cov = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(initial.covariance.data());
  ekf_.reset(initial.pose, cov, 0.0,
             config_.initial_bias_sigma_radps * config_.initial_bias_sigma_radps);
  lcakf_.reset(initial.pose.x_m, initial.pose.y_m, 0.0);
  lcakf_.set_position(initial.pose.x_m, initial.pose.y_m, cov(0, 0), cov(1, 1));
  lcakf_yaw_var_ = cov(2, 2);
  eg_.reset(initial.pose);
}

Status KalmanLocalization::hand_over(const PoseEstimate& current) noexcept {
  const Pose2& p = current.pose;
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.yaw_rad)) {
    return fail("kalman: non-finite pose handed over");
  }
  // The outgoing plugin's covariance, or the documented hand-over default when it has none.
  Matrix3 cov = Matrix3::Zero();
  if (current.has_covariance) {
    cov = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(current.covariance.data());
  } else {
    const double pos_var = config_.handover_position_sigma_m * config_.handover_position_sigma_m;
    cov.diagonal() << pos_var, pos_var,
        config_.handover_yaw_sigma_rad * config_.handover_yaw_sigma_rad;
  }
  if (config_.mode == KalmanMode::kEkf) {
    const localization::EkfResult r = ekf_.set_pose(p, &cov);
    if (r == localization::EkfResult::kNonFinite)
      return fail("kalman: non-finite covariance handed over");
    if (r == localization::EkfResult::kNotPsd)
      return fail("kalman: handed-over covariance is not positive semi-definite");
  } else {
    if (!cov.allFinite()) return fail("kalman: non-finite covariance handed over");
    lcakf_.set_position(p.x_m, p.y_m, cov(0, 0), cov(1, 1));
    lcakf_yaw_var_ = cov(2, 2);
  }
  eg_.reset(p);
  return Status::kOk;
}

Status KalmanLocalization::update(const OdometryIncrement& odometry,
                                  const HardwareState& readings) noexcept {
  if (!odometry.valid) return Status::kOk;
  const bool gyro_valid = readings.gyro_valid;
  const double gyro_radps =
      (readings.gyro_wz_radps - config_.eg.gyro_bias_radps) / config_.eg.gyro_scale;

  if (config_.mode == KalmanMode::kEkf) {
    localization::EkfResult r = ekf_.step(odometry.delta, odometry.dt_s, gyro_radps, gyro_valid);
    if (r == localization::EkfResult::kOk && config_.use_pose_fixes &&
        readings.motion_capture.valid) {
      r = ekf_.update_pose_fix(readings.motion_capture.pose);
    }
    if (r == localization::EkfResult::kNonFinite)
      return fail("kalman: non-finite odometry, gyro or pose fix");
    if (r == localization::EkfResult::kNotPsd)
      return fail("kalman: covariance is not positive semi-definite");
    return Status::kOk;
  }

  if (!eg_.step(odometry.delta, odometry.dt_s, readings.gyro_wz_radps, gyro_valid)) {
    return fail("kalman: non-finite odometry increment or gyro rate");
  }
  const Pose2 measured = eg_.pose();
  if (!lcakf_.step(odometry.dt_s, measured.x_m, measured.y_m)) {
    return fail("kalman: lcakf step rejected (non-finite input or covariance not PSD)");
  }
  // Heading variance of the E/G the filter passes through: the same per-step noise model
  // as the EKF uses for whichever source the heading came from.
  const localization::EkfNoise& n = config_.ekf;
  if (eg_.last_step_used_gyro()) {
    const double sd = n.gyro_noise_radps * odometry.dt_s;
    lcakf_yaw_var_ += sd * sd;
  } else {
    lcakf_yaw_var_ += n.rotation_rad_per_sqrt_rad * n.rotation_rad_per_sqrt_rad *
                          std::abs(odometry.delta.yaw_rad) +
                      n.yaw_rad_per_sqrt_m * n.yaw_rad_per_sqrt_m *
                          std::hypot(odometry.delta.x_m, odometry.delta.y_m);
  }
  lcakf_yaw_var_ = std::min(lcakf_yaw_var_, kBig);
  return Status::kOk;
}

PoseEstimate KalmanLocalization::estimate() const noexcept {
  PoseEstimate e;
  e.has_covariance = true;
  if (config_.mode == KalmanMode::kEkf) {
    e.pose = ekf_.pose();
    ekf_.pose_covariance(e.covariance);
    return e;
  }
  e.pose = Pose2{lcakf_.x_m(), lcakf_.y_m(), eg_.pose().yaw_rad};
  e.covariance = {};
  e.covariance[0] = lcakf_.covariance_x()(0, 0);
  e.covariance[4] = lcakf_.covariance_y()(0, 0);
  e.covariance[8] = lcakf_yaw_var_;
  return e;
}

}  // namespace swivel::plugins

SWIVEL_EXPORT_PLUGIN(swivel::plugins::KalmanLocalization, swivel::Localization, "kalman")
