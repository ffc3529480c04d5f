// SPDX-License-Identifier: Apache-2.0
#pragma once
// The `dynamixel` hardware plugin: wheels (and SWPC steering) driven by DYNAMIXEL X-series
// servos on one Protocol 2.0 bus. Configuration: README.md in this folder.
//
// A bus thread (started by activate(), joined by deactivate()) runs one bus cycle per
// bus_period_s: a Sync Write of the goals (Goal Velocity of the wheel servos; Goal Position
// of the steering servos, when there are any) and one Sync Read of Present Velocity and
// Present Position of every servo; a status with the alert bit set is followed by a READ of
// Hardware Error Status. read() and write() only exchange with that thread through lock-free
// latest-value buffers.
//
// The servos' Bus Watchdog (address 98) is armed at activation with bus_watchdog_s, fed by
// every bus cycle and disarmed at deactivation: when the daemon dies, the servos stop by
// themselves within that time.
//
// Faults (read() returns kError with a fixed message naming the servo, or the port;
// latched until a clear re-activates): a status packet missing or later than
// reply_timeout_s; max_crc_errors consecutive bad CRCs from one servo; a hardware error bit
// (with its meaning); an error number in a status; a servo's bus watchdog expired; a wheel
// goal beyond a servo's Velocity Limit (unless clamped); the port failed (an unplugged
// adapter: a clear closes and reopens it); no new reading from the bus thread for
// stale_timeout_s. From the fault on, the bus thread commands zero wheel velocity and holds
// the steering itself.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "swivel/dynamixel/bus.hpp"
#include "swivel/dynamixel/serial_port.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/rt/latest_value.hpp"

namespace swivel::plugins {

class DynamixelHardware final : public Hardware {
 public:
  static constexpr std::size_t kMaxServos = std::size_t{2} * kMaxModules;

  enum class FaultKind : std::uint8_t {
    kNone,
    kSilent,
    kCrcRun,
    kHardwareError,
    kStatusError,
    kWatchdog,
    kVelocityLimit,
    kPort,
  };
  static constexpr std::size_t kFaultKinds = 8;
  /// The hardware-error meanings a message exists for (hardware_error_text()).
  static constexpr std::size_t kHardwareTexts = 6;

  struct Servo {
    std::uint8_t id = 0;
    bool steering = false;  ///< extended position mode; else a wheel in velocity mode
    std::uint32_t module = 0;
    double direction = 1.0;        ///< +1 or -1: servo positive = output positive
    double gear_ratio = 1.0;       ///< servo revolutions per output revolution
    double zero_offset_rad = 0.0;  ///< output angle = servo angle / ratio - offset
    std::string name;              ///< "left wheel", "wheel 2", "steer 2"
    // Read at activation.
    std::uint16_t model = 0;
    std::int32_t velocity_limit = 0;  ///< Velocity Limit (44), 0.229 rpm units
  };

  /// The quickest bus exchange of a sliding window (between one and two blocks of block_s):
  /// a lasting rise in latency (a busier host, a slower adapter) becomes the new floor within
  /// two blocks, where an all-time minimum would leave every later reading untimed.
  class ExchangeFloor {
   public:
    explicit ExchangeFloor(double block_s) noexcept : block_s_(block_s) {}
    void add(double now_s, double exchange_s) noexcept;
    [[nodiscard]] double value() const noexcept;

   private:
    double block_s_;
    double block_start_s_ = -1e300;
    double current_ = 1e300;
    double previous_ = 1e300;
  };
  /// Block of ExchangeFloor in the bus thread: a lasting latency change is learnt in 0.5 s at
  /// most; each block holds some 125 exchanges at the default 2 ms bus period.
  static constexpr double kExchangeFloorBlockS = 0.25;
  /// How often the bus thread reads Bus Watchdog back from every servo (besides after a late
  /// cycle): a servo whose watchdog expired refuses goals without a word.
  static constexpr double kWatchdogReadbackS = 0.25;
  /// Start-up exchanges (ping, reads, writes of activate() and deactivate()) are tried this
  /// often before one that gets no good status refuses.
  static constexpr int kSetupAttempts = 3;

  /// Off the loop. A warning when `port` (resolved through symbolic links) is a USB serial
  /// adapter whose latency timer under `sysfs_root` (/sys/bus/usb-serial/devices/<tty>/
  /// latency_timer) is above 1 ms: each reply then waits up to that long. "" otherwise.
  static std::string latency_timer_warning(const std::string& port,
                                           const std::string& sysfs_root = "/sys");
  /// The X-series model with this model number ("XM430-W350"), or nullptr.
  static const char* model_name(std::uint16_t model) noexcept;

  /// How much longer than the quickest exchange one may take with its sampling time still
  /// known: at the 20 rad/s wheel limit, 2 ms of timing error moves a wheel 0.04 rad, a third
  /// of the differential drivetrain's one-cycle jump bound at 500 Hz.
  static constexpr double kSampleTimingSlackS = 0.002;

  /// What the bus thread publishes once per bus cycle.
  struct Reading {
    std::uint64_t cycle = 0;
    double stamp_s = 0.0;   ///< CLOCK_MONOTONIC at the end of the Sync Read
    double sample_s = 0.0;  ///< CLOCK_MONOTONIC the servos sampled (estimated)
    /// The exchange took no longer than the quickest one plus kSampleTimingSlackS, so
    /// sample_s is known to within that; a longer one (the host or device was busy in it)
    /// leaves the sampling instant anywhere in it.
    bool sample_time_known = true;
    std::array<std::int32_t, kMaxServos> position{};  ///< servo counts
    std::array<std::int32_t, kMaxServos> velocity{};  ///< 0.229 rpm units
    /// CLOCK_MONOTONIC the servo sampled position[i] and velocity[i] (estimated): a servo
    /// whose reply failed (bad CRC) keeps its last values and their time.
    std::array<double, kMaxServos> servo_sample_s{};
    /// Each module's steering goal (output angle) as written in this cycle, and when.
    std::array<double, kMaxModules> steer_goal_rad{};
    double goal_s = 0.0;
    FaultKind fault = FaultKind::kNone;
    std::uint8_t fault_servo = 0;
    std::uint8_t hardware_error = 0;
    std::uint64_t crc_errors = 0;  ///< bad status packets since activation
    double cycle_busy_s = 0.0;     ///< Sync Write + Sync Read of this cycle
  };

  DynamixelHardware() = default;
  ~DynamixelHardware() override;
  // It owns a bus thread that points back at it.
  DynamixelHardware(const DynamixelHardware&) = delete;
  DynamixelHardware& operator=(const DynamixelHardware&) = delete;
  DynamixelHardware(DynamixelHardware&&) = delete;
  DynamixelHardware& operator=(DynamixelHardware&&) = delete;

  void configure(const PluginContext& ctx) override;
  Status activate() override;
  Status deactivate() override;
  void on_error(const char* cause) noexcept override;
  Status read(double stamp_s, HardwareState& out) noexcept override;
  Status write(const ActuatorCommand& command) noexcept override;
  [[nodiscard]] const char* last_error() const noexcept override { return last_error_; }

  /// Real-time safe. The fixed message of a fault of servo `servo` (index into servos()).
  [[nodiscard]] const char* message(FaultKind kind, std::size_t servo,
                                    std::uint8_t hardware_error) const noexcept;

  // For tests and benches.
  [[nodiscard]] const std::vector<Servo>& servos() const noexcept { return servos_; }
  [[nodiscard]] const Reading& last_reading() const noexcept { return reading_; }
  [[nodiscard]] std::uint64_t bus_cycles() const noexcept {
    return bus_cycles_.load(std::memory_order_relaxed);
  }

 private:
  void stop_thread() noexcept;
  void bus_loop(Reading r) noexcept;  // starts from the activation reading
  // Off the loop: a failed step of activate()/deactivate() names the servo; false then.
  bool setup_servo(dynamixel::Bus& bus, std::size_t i);
  // Off the loop: refuses (false, activate_error_ set) or warns about a configured maximum
  // rate above a servo's Velocity Limit.
  bool check_velocity_limits();
  bool arm_watchdogs(dynamixel::Bus& bus);
  void read_drivetrain_limits(const PluginContext& ctx);
  [[nodiscard]] std::int32_t wheel_goal(std::size_t i, double rate_radps) const noexcept;
  [[nodiscard]] std::int32_t steer_goal(std::size_t i, double angle_rad) const noexcept;
  [[nodiscard]] double output_angle(std::size_t i, std::int32_t counts) const noexcept;
  // Output angle of servo `servo` (-1: none, 0) extrapolated from its sample to `stamp_s`.
  [[nodiscard]] double angle_at(std::int32_t servo, double stamp_s) const noexcept;
  // Module m's steering angle at `stamp_s`: extrapolated as angle_at(), but no further than
  // its goal, which a position servo does not pass.
  [[nodiscard]] double steer_angle_at(std::uint32_t m, double stamp_s) const noexcept;

  // Configuration.
  std::string port_path_;
  std::uint32_t baud_ = 1000000;
  double reply_timeout_s_ = 0.005;
  double bus_period_s_ = 0.002;
  double stale_timeout_s_ = 0.05;
  std::uint32_t max_crc_errors_ = 3;
  double bus_watchdog_s_ = 0.1;
  std::uint8_t watchdog_units_ = 5;  // Bus Watchdog (98) value, 20 ms each; 0: off
  bool clamp_to_velocity_limit_ = false;
  // The drivetrain's configured maxima (from the daemon configuration), 0 when unknown, and
  // the keys they came from, for messages.
  double max_wheel_rate_radps_ = 0.0;
  double max_steer_rate_radps_ = 0.0;
  std::string max_wheel_rate_key_, max_steer_rate_key_;
  double loop_period_s_ = 0.001;
  std::uint32_t module_count_ = 0;
  std::vector<Servo> servos_;
  std::vector<std::uint8_t> wheel_ids_, steer_ids_, all_ids_;
  std::vector<std::size_t> wheel_index_, steer_index_;   // into servos_
  std::array<std::int32_t, kMaxModules> wheel_servo_{};  // module -> servo index, -1 none
  std::array<std::int32_t, kMaxModules> steer_servo_{};
  // Messages, built by configure(): [servo][kind] and [servo][hardware text].
  std::vector<std::array<std::string, kFaultKinds>> messages_;
  std::string port_message_;  // the port failed
  std::vector<std::array<std::string, kHardwareTexts>> hardware_messages_;
  std::string activate_error_;  // activate()/deactivate() failures (off the loop)

  // Bus thread.
  dynamixel::SerialPort port_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> hold_{false};  // on_error(): zero goals until re-activated
  std::atomic<std::uint64_t> bus_cycles_{0};
  rt::LatestValue<ActuatorCommand> commands_;          // loop -> bus thread
  rt::LatestValue<Reading> readings_;                  // bus thread -> loop
  std::array<double, kMaxModules> start_steer_rad_{};  // steering at activation
  std::array<std::int32_t, kMaxServos> goal_limit_{};  // wheel goal bound, 0.229 rpm units

  // Loop side.
  Reading reading_{};  ///< the newest reading: its faults count
  Reading timed_{};    ///< the newest with a known sampling time: the angles come from it
  std::uint32_t cycles_without_reading_ = 0;
  std::array<double, kMaxModules> commanded_steer_rate_{};  ///< as last written, 0 locked
  std::uint32_t stale_cycles_ = 50;
  const char* last_error_ = "";
};

}  // namespace swivel::plugins
