// SPDX-License-Identifier: Apache-2.0
#pragma once
// Hardware plugin: sensor readings in, actuator setpoints out.
//
// Lifecycle (after ros2_control's hardware components). The host guarantees this order and
// never calls two methods of one instance at the same time:
//
//   unconfigured --configure()--> inactive --activate()--> active --deactivate()--> inactive
//                                                            |  ^
//                                   read()/write() fails:    |  | activate(), on a clear
//                                   on_error() at the loop's v  | (`swivelctl clear`)
//                                   cycle boundary         error
//
//  - unconfigured: created. configure() reads the parameters; the actuators stay off.
//  - inactive: configured, or deactivated. Neither read() nor write() is called. The
//    instance is destroyed from here (or from unconfigured).
//  - active: activate() succeeded (drives enabled after the plugin's own checks). The loop
//    calls read() and write() once per cycle; nothing else is called meanwhile.
//  - error: a read() or write() returned kError (or threw), or a reading had more modules
//    than the loop can take (every hardware_error fault). The loop calls on_error() once,
//    on the loop thread, right after that cycle's write; it then stops the robot (zero
//    setpoints) and keeps calling read() and write() so that it sees the hardware answer
//    again. A clear requested by the operator pauses the loop's hardware calls at a cycle
//    boundary, calls activate() off the loop and resumes: kOk returns to active, kError
//    refuses the clear with last_error() and stays in error.
//  - deactivate() is called off the loop after the loop's last cycle, which commanded zero
//    velocity (on SIGTERM or SIGINT the robot has been brought to rest first), from active
//    or error.
//
// activate() and deactivate() run off the loop and may block (a bus transaction, a drive's
// enable sequence); read(), write() and on_error() are real-time methods.

#include "swivel/plugin/abi.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/types.hpp"

namespace swivel {

class Hardware {
 public:
  virtual ~Hardware() = default;

  /// Off the loop. unconfigured -> inactive. Reads and validates ctx.params.
  /// @throws ConfigError naming the key; std::exception for other start-up failures.
  virtual void configure(const PluginContext& ctx) = 0;

  /// Off the loop (may block). inactive -> active, or error -> active on a clear: enable the
  /// drives once the hardware is ready. kError (with last_error()) leaves the state as it
  /// was; at start-up the daemon then exits with that message. The default does nothing.
  virtual Status activate() { return Status::kOk; }

  /// Off the loop (may block). active or error -> inactive, after the loop's last cycle
  /// wrote zero setpoints: de-energise the drives. kError is logged with last_error(); the
  /// instance is destroyed afterwards either way. The default does nothing.
  virtual Status deactivate() { return Status::kOk; }

  /// Real-time safe, on the loop thread at the end of the cycle in which read() or write()
  /// failed: active -> error. `cause` is that failure's message (static storage). Put the
  /// actuators in a safe state without blocking; read() and write() are still called
  /// afterwards. Called once per entry into the error state. The default does nothing.
  virtual void on_error(const char* /*cause*/) {}

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

// The fingerprint SWIVEL_EXPORT_PLUGIN puts in the descriptor; it needs this interface whole.
#include "swivel/plugin/abi_fingerprint.hpp"  // IWYU pragma: export
