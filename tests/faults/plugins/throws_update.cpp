// SPDX-License-Identifier: Apache-2.0
// Breaks the real-time rule on purpose: update() throws after `throw_after_cycles` good
// cycles (params). The loop must catch it at the plugin boundary.
#include <stdexcept>

#include "swivel/config/param_reader.hpp"
#include "swivel/plugin/localization.hpp"

namespace swivel::fault_plugins {

class ThrowsInUpdate final : public Localization {
 public:
  void configure(const PluginContext& ctx) override {
    ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
    throw_after_cycles_ = params.integer_or("throw_after_cycles", 0, 0, 1000000000);
    params.finish();
  }
  void reset(const PoseEstimate& initial) override { estimate_ = initial; }
  Status hand_over(const PoseEstimate& current) noexcept override {
    estimate_ = current;
    return Status::kOk;
  }
  // Deliberately not noexcept.
  Status update(const OdometryIncrement& odometry, const HardwareState& /*readings*/) override {
    if (cycles_++ >= throw_after_cycles_) throw std::runtime_error("planted exception in update");
    if (odometry.valid) estimate_.pose.x_m += odometry.delta.x_m;
    return Status::kOk;
  }
  [[nodiscard]] PoseEstimate estimate() const noexcept override { return estimate_; }

 private:
  PoseEstimate estimate_;
  int throw_after_cycles_ = 0;
  int cycles_ = 0;
};

}  // namespace swivel::fault_plugins

SWIVEL_EXPORT_PLUGIN(swivel::fault_plugins::ThrowsInUpdate, swivel::Localization, "throws_update")
