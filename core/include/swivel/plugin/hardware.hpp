#pragma once
// Hardware plugin: sensor readings in, actuator setpoints out.

#include "swivel/plugin/abi.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/types.hpp"

namespace swivel {

class Hardware {
 public:
  virtual ~Hardware() = default;

  /// Off the loop. Reads and validates ctx.params.
  /// @throws ConfigError naming the key; std::exception for other start-up failures.
  virtual void configure(const PluginContext& ctx) = 0;

  /// Real-time safe. Fills `out` with the readings at monotonic time `stamp_s`.
  /// A simulated robot advances its world to `stamp_s` under the last written command.
  virtual Status read(double stamp_s, HardwareState& out) = 0;

  /// Real-time safe. Applies setpoints until the next write.
  virtual Status write(const ActuatorCommand& command) = 0;

  /// Real-time safe. The true pose where the hardware knows it (simulation), else false.
  virtual bool ground_truth(Pose2& /*out*/) const noexcept { return false; }

  /// Real-time safe. A static message describing the last kError.
  [[nodiscard]] virtual const char* last_error() const noexcept { return ""; }
};

}  // namespace swivel
