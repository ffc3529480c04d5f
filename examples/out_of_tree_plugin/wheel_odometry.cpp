// SPDX-License-Identifier: Apache-2.0
// wheel_odometry: a localization plugin that integrates the drivetrain's odometry alone,
// ignoring the gyro, with a configurable scale on the travelled distance. Small on
// purpose: it shows the whole contract of a localization plugin built out of tree.
//
// swiveld.yaml:
//   localization:
//     plugin: wheel_odometry
//     params: {distance_scale: 1.0}

#include <cmath>
#include <swivel/config/param_reader.hpp>
#include <swivel/plugin/localization.hpp>
#include <swivel/pose_math.hpp>

namespace example {

class WheelOdometry final : public swivel::Localization {
 public:
  // Off the loop: read and check the parameters (ConfigError names a bad key).
  void configure(const swivel::PluginContext& ctx) override {
    swivel::ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
    distance_scale_ = params.number_or("distance_scale", 1.0, 0.5, 2.0);
    params.finish();
  }

  void reset(const swivel::PoseEstimate& initial) override { pose_ = initial.pose; }

  // Real-time safe from here on: no allocation, no exception, no I/O.
  swivel::Status hand_over(const swivel::PoseEstimate& current) noexcept override {
    if (!std::isfinite(current.pose.x_m) || !std::isfinite(current.pose.y_m) ||
        !std::isfinite(current.pose.yaw_rad)) {
      error_ = "wheel_odometry: non-finite pose handed over";
      return swivel::Status::kError;
    }
    pose_ = current.pose;
    return swivel::Status::kOk;
  }

  swivel::Status update(const swivel::OdometryIncrement& odometry,
                        const swivel::HardwareState& /*readings*/) noexcept override {
    if (!odometry.valid) return swivel::Status::kOk;
    swivel::Pose2 step = odometry.delta;
    step.x_m *= distance_scale_;
    step.y_m *= distance_scale_;
    pose_ = swivel::compose(pose_, step);
    pose_.yaw_rad = swivel::wrap_pi(pose_.yaw_rad);
    return swivel::Status::kOk;
  }

  [[nodiscard]] swivel::PoseEstimate estimate() const noexcept override {
    swivel::PoseEstimate e;
    e.pose = pose_;
    return e;  // no covariance: a dead-reckoning estimate states none
  }

  [[nodiscard]] const char* last_error() const noexcept override { return error_; }

 private:
  double distance_scale_ = 1.0;
  swivel::Pose2 pose_;
  const char* error_ = "";
};

/// For the plugin's own test program (wheel_odometry_rt_test.cpp).
swivel::Localization* make_wheel_odometry() { return new WheelOdometry(); }

}  // namespace example

SWIVEL_EXPORT_PLUGIN(example::WheelOdometry, swivel::Localization, "wheel_odometry")
