#pragma once
// The `raw_eg` localization plugin: E/G dead reckoning (swivel/localization/eg_odometry.hpp)
// behind the Localization interface. No covariance.

#include "swivel/localization/eg_odometry.hpp"
#include "swivel/plugin/localization.hpp"

namespace swivel::plugins {

class RawEgLocalization final : public Localization {
 public:
  /// Off the loop. Param heading_source: gyro (default) | encoders. The gyro reading is
  /// corrected with the nominal robot model's sensors.gyro scale and bias.
  /// @throws ConfigError naming the key.
  void configure(const PluginContext& ctx) override;

  /// Configures from plain values (tests, tools).
  void configure(const localization::EgConfig& config) noexcept { eg_.set_config(config); }

  /// Off the loop.
  void reset(const PoseEstimate& initial) override { eg_.reset(initial.pose); }

  /// Real-time safe.
  Status hand_over(const PoseEstimate& current) noexcept override;

  /// Real-time safe. Ignores cycles whose odometry is not valid.
  Status update(const OdometryIncrement& odometry, const HardwareState& readings) noexcept override;

  /// Real-time safe.
  [[nodiscard]] PoseEstimate estimate() const noexcept override;

  /// Real-time safe. Static message for the last kError.
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

 private:
  localization::EgOdometry eg_;
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
