// SPDX-License-Identifier: Apache-2.0
// Refuses the hand-over: a hot swap to it must roll back, and a pose set through it must be
// refused, without a fault. `throw: true` (params) throws from hand_over() instead of
// returning kError, breaking the real-time rule on purpose.
#include <cmath>
#include <stdexcept>

#include "swivel/config/param_reader.hpp"
#include "swivel/plugin/localization.hpp"

namespace swivel::test_plugins {

class RefusesHandOver final : public Localization {
 public:
  void configure(const PluginContext& ctx) override {
    ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
    throw_ = params.boolean_or("throw", false);
    params.finish();
  }
  void reset(const PoseEstimate& initial) override { estimate_ = initial; }
  // Deliberately not noexcept: with `throw: true` it throws.
  Status hand_over(const PoseEstimate& /*current*/) override {
    if (throw_) throw std::runtime_error("planted exception in hand_over");
    return Status::kError;  // the estimate stays as it was
  }
  Status update(const OdometryIncrement& odometry,
                const HardwareState& /*readings*/) noexcept override {
    if (!odometry.valid) return Status::kOk;
    const double c = std::cos(estimate_.pose.yaw_rad);
    const double s = std::sin(estimate_.pose.yaw_rad);
    estimate_.pose.x_m += c * odometry.delta.x_m - s * odometry.delta.y_m;
    estimate_.pose.y_m += s * odometry.delta.x_m + c * odometry.delta.y_m;
    estimate_.pose.yaw_rad += odometry.delta.yaw_rad;
    return Status::kOk;
  }
  [[nodiscard]] PoseEstimate estimate() const noexcept override { return estimate_; }
  [[nodiscard]] const char* last_error() const noexcept override {
    return "no map to place the pose in (planted refusal)";
  }

 private:
  PoseEstimate estimate_;
  bool throw_ = false;
};

}  // namespace swivel::test_plugins

SWIVEL_EXPORT_PLUGIN(swivel::test_plugins::RefusesHandOver, swivel::Localization,
                     "refuses_hand_over")
