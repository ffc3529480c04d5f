// SPDX-License-Identifier: Apache-2.0
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
//   faults:                   scheduled hardware faults (docs/faults.md), up to kMaxFaults:
//     - {kind: K, start_s: T, duration_s: D, module: I, value: V}
//                             active for reads at sim time t (seconds since the first read)
//                             with T <= t < T + D. module (default 0) only for the wheel
//                             kinds, value only for out_of_range_wheel (default 100 rad).
//
// Fault kinds (the world keeps moving under the last accepted setpoints throughout):
//   nan_wheel            wheel angle of `module` reads NaN
//   inf_gyro             gyro rate reads +inf (gyro_valid stays true)
//   out_of_range_wheel   wheel angle of `module` reads `value` rad off (a jump at the start
//                        and back at the end; a one-read spike when D is one period)
//   frozen_encoder       wheel angle of `module` keeps the value of the read before the fault
//   gyro_dropout         gyro_valid false (rate 0)
//   stall                read() returns kError "sim: hardware not answering" (never blocks)
//   read_error           read() returns kError "sim: injected read error"
//   write_error          write() returns kError "sim: injected write error"; the setpoints
//                        are not applied, so the world keeps the previous ones
//
// Run-time injection: inject_fault() in-process, or from code that only holds the plugin
// instance (loaded through PluginLoader) the C entry point swivel_sim_inject_fault that the
// plugin library exports (look it up with dlsym on the library's path):
//   int swivel_sim_inject_fault(void* hardware, const char* kind, double duration_s,
//                               unsigned module, double value);
// `hardware` is the swivel::Hardware* of a sim instance. Returns 0 when accepted, 1 when
// `hardware` is not a configured sim instance, 2 for an unknown kind, 3 for a bad module,
// duration or value, 4 while the previous injection has not been taken by read(). An
// injection that finds the table full of unexpired faults is dropped and counted
// (injections_dropped()).

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "swivel/plugin/hardware.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/sim/world.hpp"

namespace swivel::plugins {

enum class SimFaultKind : std::uint8_t {
  kNanWheel,
  kInfGyro,
  kOutOfRangeWheel,
  kFrozenEncoder,
  kGyroDropout,
  kStall,
  kReadError,
  kWriteError,
};

/// The `kind:` names, in SimFaultKind order.
inline constexpr std::array<const char*, 8> kSimFaultKindNames = {
    "nan_wheel",    "inf_gyro", "out_of_range_wheel", "frozen_encoder",
    "gyro_dropout", "stall",    "read_error",         "write_error"};

/// The kind named `name`, or nullopt. Real-time safe.
std::optional<SimFaultKind> sim_fault_kind(const char* name) noexcept;

/// One fault of the simulated hardware.
struct SimFault {
  SimFaultKind kind = SimFaultKind::kReadError;
  double start_s = 0.0;      ///< sim time (since the first read) it becomes active
  double duration_s = 0.0;   ///< active for reads with start_s <= t < start_s + duration_s
  std::uint32_t module = 0;  ///< wheel kinds: which module's encoder
  double value_rad = 100.0;  ///< out_of_range_wheel: the jump
};

class SimHardware final : public Hardware {
 public:
  static constexpr std::size_t kMaxFaults = 32;
  /// params.max_substeps_per_read: physics per read() is bounded to this many substeps
  /// (50 ms at the default 1 ms substep); a longer gap is caught up over later reads.
  static constexpr std::int64_t kDefaultMaxSubstepsPerRead = 50;

  void configure(const PluginContext& ctx) override;
  /// Real-time safe. The first call only starts the clock; later calls advance the world
  /// towards `stamp_s` under the last written command (at most max_substeps_per_read
  /// substeps per call; the reading is stamped with the time the world reached), then apply
  /// active faults.
  Status read(double stamp_s, HardwareState& out) noexcept override;
  /// Real-time safe. kError for a non-finite setpoint, a wrong module count or an active
  /// write_error fault.
  Status write(const ActuatorCommand& command) noexcept override;
  bool ground_truth(Pose2& out) const noexcept override;
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

  /// Any one thread (single producer), real-time safe. Schedules `kind` from the next read()
  /// for `duration_s`. False for a bad module, duration or value, or while the previous
  /// injection has not been taken by read().
  bool inject_fault(SimFaultKind kind, double duration_s, std::uint32_t module = 0,
                    double value_rad = 100.0) noexcept;

  /// The world (for tests); null before configure().
  [[nodiscard]] const sim::World* world() const noexcept { return world_ ? &*world_ : nullptr; }
  /// Sim time the world has reached (seconds since the first read).
  [[nodiscard]] double sim_time_s() const noexcept { return world_stamp_s_ - start_stamp_s_; }
  /// How far the world is behind the last read's stamp (0 unless catching up after a gap).
  [[nodiscard]] double behind_s() const noexcept { return last_stamp_s_ - world_stamp_s_; }
  /// Any thread. Injections read() found no free slot for.
  [[nodiscard]] std::uint64_t injections_dropped() const noexcept {
    return injections_dropped_.load(std::memory_order_relaxed);
  }

 private:
  struct ActiveFault {
    SimFault fault;
    bool frozen = false;  // frozen_encoder: value captured
    double frozen_rad = 0.0;
  };

  [[nodiscard]] static bool active(const SimFault& fault, double t_s) noexcept;
  void take_injection(double t_s) noexcept;
  Status apply_faults(double t_s, HardwareState& out) noexcept;

  std::optional<sim::World> world_;
  ActuatorCommand command_{};
  bool started_ = false;
  double start_stamp_s_ = 0.0;
  double last_stamp_s_ = 0.0;   ///< stamp of the last read
  double world_stamp_s_ = 0.0;  ///< daemon time the world has reached
  double max_step_s_ = 0.05;    ///< physics per read at most
  const char* last_error_ = "";

  std::array<ActiveFault, kMaxFaults> faults_{};
  std::size_t fault_count_ = 0;
  std::array<double, kMaxModules> last_wheel_rad_{};  // previous read's reported angles
  // Injection mailbox: written by the injecting thread, taken by read().
  SimFault injected_{};
  std::atomic<bool> injection_pending_{false};
  std::atomic<std::uint64_t> injections_dropped_{0};
};

}  // namespace swivel::plugins
