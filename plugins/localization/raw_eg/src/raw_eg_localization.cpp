// SPDX-License-Identifier: Apache-2.0
#include "raw_eg_localization.hpp"

#include <Eigen/Core>
#include <cmath>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/localization/eg_params.hpp"
#include "swivel/plugin/abi.hpp"

namespace swivel::plugins {
namespace {

using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

}  // namespace

void RawEgLocalization::configure(const PluginContext& ctx) {
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  const localization::EgConfig config = localization::read_eg_config(params, ctx.robot);
  const localization::EgNoise noise = localization::read_eg_noise(params, ctx.robot);
  params.finish();
  configure(config, noise);
}

void RawEgLocalization::configure(const localization::EgConfig& config,
                                  const localization::EgNoise& noise) noexcept {
  eg_.set_config(config);
  cov_.set_noise(noise);
  eg_.reset(Pose2{});
  cov_.reset(Eigen::Matrix3d::Zero());
}

void RawEgLocalization::reset(const PoseEstimate& initial) {
  eg_.reset(initial.pose);
  cov_.reset(Eigen::Matrix3d::Zero());
  if (initial.has_covariance) {
    (void)cov_.set_pose_covariance(Eigen::Map<const RowMajor3>(initial.covariance.data()));
  }
}

Status RawEgLocalization::hand_over(const PoseEstimate& current) noexcept {
  const Pose2& p = current.pose;
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.yaw_rad)) {
    last_error_ = "raw_eg: non-finite pose handed over";
    return Status::kError;
  }
  if (current.has_covariance) {
    const Eigen::Matrix3d handed = Eigen::Map<const RowMajor3>(current.covariance.data());
    if (!localization::is_covariance(handed)) {
      last_error_ = "raw_eg: handed-over covariance is not finite and positive semi-definite";
      return Status::kError;
    }
    (void)cov_.set_pose_covariance(handed);
  }
  eg_.reset(p);
  return Status::kOk;
}

Status RawEgLocalization::update(const OdometryIncrement& odometry,
                                 const HardwareState& readings) noexcept {
  if (!odometry.valid) return Status::kOk;
  if (!eg_.step(odometry.delta, odometry.dt_s, readings.gyro_wz_radps, readings.gyro_valid)) {
    last_error_ = "raw_eg: non-finite odometry increment or gyro rate";
    return Status::kError;
  }
  cov_.step(odometry.delta, odometry.dt_s, eg_.last_chord_yaw_rad(), eg_.last_step_used_gyro());
  return Status::kOk;
}

PoseEstimate RawEgLocalization::estimate() const noexcept {
  PoseEstimate e;
  e.pose = eg_.pose();
  cov_.pose_covariance(e.covariance);
  e.has_covariance = true;
  return e;
}

}  // namespace swivel::plugins

SWIVEL_EXPORT_PLUGIN(swivel::plugins::RawEgLocalization, swivel::Localization, "raw_eg")
