#pragma once
// The `sim` hardware plugin: a thin adapter that runs a sim::World on the daemon's clock.
//
// params (all optional):
//   true_model: FILE          robot model of the world (relative to the config file's
//                             directory); default: the nominal robot model
//   seed: 1                   random streams (sensor noise, non-systematic errors)
//   motion_capture: true      produce motion-capture samples at the model's rate
//   sensor_noise: true        gyro and motion-capture noise from the model
//   substep_s: 0.001          integration step, s
//   slip: {wheel_std: 0, lateral_scrub_std: 0, correlation_time_s: 0.5}
//                             non-systematic errors (see sim::NonSystematicErrors)

#include <optional>

#include "swivel/plugin/hardware.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/sim/world.hpp"

namespace swivel::plugins {

class SimHardware final : public Hardware {
 public:
  void configure(const PluginContext& ctx) override;
  /// Real-time safe. The first call only starts the clock; later calls advance the world
  /// from the previous stamp under the last written command.
  Status read(double stamp_s, HardwareState& out) noexcept override;
  /// Real-time safe. kError for a non-finite setpoint or a wrong module count.
  Status write(const ActuatorCommand& command) noexcept override;
  bool ground_truth(Pose2& out) const noexcept override;
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

  /// The world (for tests); null before configure().
  [[nodiscard]] const sim::World* world() const noexcept { return world_ ? &*world_ : nullptr; }

 private:
  std::optional<sim::World> world_;
  ActuatorCommand command_{};
  bool started_ = false;
  double start_stamp_s_ = 0.0;
  double last_stamp_s_ = 0.0;
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
