// SPDX-License-Identifier: Apache-2.0
#pragma once
// A dead-simple localization that integrates odometry; the test plugins override one
// behaviour each.

#include <cmath>

#include "swivel/plugin/localization.hpp"

namespace swivel::test_plugins {

class TestLocalization : public Localization {
 public:
  void configure(const PluginContext& /*ctx*/) override {}
  void reset(const PoseEstimate& initial) override { estimate_ = initial; }
  Status hand_over(const PoseEstimate& current) noexcept override {
    estimate_ = current;
    return Status::kOk;
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

 protected:
  PoseEstimate estimate_;
};

}  // namespace swivel::test_plugins
