// SPDX-License-Identifier: Apache-2.0
#include "lsm_localization.hpp"

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

void LsmLocalization::configure(const PluginContext& ctx) {
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  localization::LsmConfig lsm;
  lsm.mode = params.choice_or("mode", "paper", {"paper", "heading_aligned"}) == "paper"
                 ? localization::LsmMode::kPaper
                 : localization::LsmMode::kHeadingAligned;
  lsm.window_points = static_cast<std::size_t>(
      params.integer_or("window_points", 10, 3, static_cast<int>(localization::kMaxWindowPoints)));
  // A period alone means time decimation only; both given means whichever comes first.
  const bool has_period = params.has("sample_period_s");
  const bool has_distance = params.has("sample_distance_m");
  lsm.sample_distance_m =
      params.number_or("sample_distance_m", has_period && !has_distance ? 0.0 : 0.02, 0.0, 10.0);
  lsm.sample_period_s = params.number_or("sample_period_s", 0.0, 0.0, 10.0);
  lsm.max_window_heading_change_rad =
      params.number_or("max_window_heading_change_rad", 0.1, 1e-6, 3.2);
  const localization::EgConfig eg = localization::read_eg_config(params, ctx.robot);
  const localization::EgNoise noise = localization::read_eg_noise(params, ctx.robot);
  params.finish();
  configure(eg, lsm, noise);
}

void LsmLocalization::configure(const localization::EgConfig& eg,
                                const localization::LsmConfig& lsm,
                                const localization::EgNoise& noise) noexcept {
  eg_.set_config(eg);
  cov_.set_noise(noise);
  lsm_.configure(lsm);
  eg_.reset(Pose2{});
  cov_.reset(Eigen::Matrix3d::Zero());
}

void LsmLocalization::reset(const PoseEstimate& initial) {
  eg_.reset(initial.pose);
  cov_.reset(Eigen::Matrix3d::Zero());
  if (initial.has_covariance) {
    (void)cov_.set_pose_covariance(Eigen::Map<const RowMajor3>(initial.covariance.data()));
  }
  lsm_.reset();
}

Status LsmLocalization::hand_over(const PoseEstimate& current) noexcept {
  const Pose2& p = current.pose;
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.yaw_rad)) {
    last_error_ = "lsm: non-finite pose handed over";
    return Status::kError;
  }
  if (current.has_covariance) {
    const Eigen::Matrix3d handed = Eigen::Map<const RowMajor3>(current.covariance.data());
    if (!localization::is_covariance(handed)) {
      last_error_ = "lsm: handed-over covariance is not finite and positive semi-definite";
      return Status::kError;
    }
    (void)cov_.set_pose_covariance(handed);
  }
  eg_.reset(p);
  lsm_.reset();
  return Status::kOk;
}

Status LsmLocalization::update(const OdometryIncrement& odometry,
                               const HardwareState& readings) noexcept {
  if (!odometry.valid) return Status::kOk;
  if (!eg_.step(odometry.delta, odometry.dt_s, readings.gyro_wz_radps, readings.gyro_valid)) {
    last_error_ = "lsm: non-finite odometry increment or gyro rate";
    return Status::kError;
  }
  cov_.step(odometry.delta, odometry.dt_s, eg_.last_chord_yaw_rad(), eg_.last_step_used_gyro());
  // The loop's own time when the hardware gives none keeps period decimation working.
  stamp_s_ = readings.stamp_s > 0.0 ? readings.stamp_s : stamp_s_ + odometry.dt_s;
  lsm_.push(eg_.pose(), eg_.unwrapped_yaw_rad(), eg_.distance_m(), stamp_s_);
  return Status::kOk;
}

PoseEstimate LsmLocalization::estimate() const noexcept {
  PoseEstimate e;
  const Pose2 eg = eg_.pose();
  e.pose = lsm_.output(eg);
  cov_.pose_covariance(e.covariance);
  // The compensation's shift, counted as uncertainty (see the header).
  const double cx = e.pose.x_m - eg.x_m;
  const double cy = e.pose.y_m - eg.y_m;
  e.covariance[0] += cx * cx;
  e.covariance[1] += cx * cy;
  e.covariance[3] += cx * cy;
  e.covariance[4] += cy * cy;
  e.has_covariance = true;
  return e;
}

}  // namespace swivel::plugins

SWIVEL_EXPORT_PLUGIN(swivel::plugins::LsmLocalization, swivel::Localization, "lsm")
