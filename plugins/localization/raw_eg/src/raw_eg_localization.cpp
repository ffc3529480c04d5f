#include "raw_eg_localization.hpp"

#include <cmath>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/localization/eg_params.hpp"
#include "swivel/plugin/abi.hpp"

namespace swivel::plugins {

void RawEgLocalization::configure(const PluginContext& ctx) {
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  const localization::EgConfig config = localization::read_eg_config(params, ctx.robot);
  params.finish();
  eg_.set_config(config);
}

Status RawEgLocalization::hand_over(const PoseEstimate& current) noexcept {
  const Pose2& p = current.pose;
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.yaw_rad)) {
    last_error_ = "raw_eg: non-finite pose handed over";
    return Status::kError;
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
  return Status::kOk;
}

PoseEstimate RawEgLocalization::estimate() const noexcept {
  PoseEstimate e;
  e.pose = eg_.pose();
  e.has_covariance = false;
  return e;
}

}  // namespace swivel::plugins

SWIVEL_EXPORT_PLUGIN(swivel::plugins::RawEgLocalization, swivel::Localization, "raw_eg")
