// SPDX-License-Identifier: Apache-2.0
// A differential robot's hardware that writes down the order in which the host calls it:
// its lifecycle hooks, the first read/write after each of them, and every call the
// lifecycle forbids (read or write while inactive, two calls at once, deactivation while the
// last setpoints still move the robot). The wheels turn at exactly the written rates and the
// gyro reads the yaw rate they imply (the robot model's geometry), so the loop's odometry
// check stays quiet.
//
// Exported for tests (dlsym on the library, which the test keeps loaded):
//   int swivel_lifecycle_journal(char* out, unsigned size)
//       the newest instance's journal, e.g. "configure activate io on_error activate io
//       deactivate"; returns the number of entries
//   int swivel_lifecycle_set(const char* what, int on)
//       "fail_reads": read() returns kError while on; "refuse_activate": activate() returns
//       kError while on. Returns 0, or 1 for an unknown switch.

#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/plugin/hardware.hpp"

namespace swivel::test_plugins {
namespace {

enum class Event : std::uint8_t {
  kConfigure,
  kActivate,
  kActivateRefused,
  kIo,  // the first read or write after a lifecycle call
  kOnError,
  kDeactivate,
  kDeactivateWhileMoving,  // the last write before deactivate() had non-zero rates
  kIoWhileInactive,
  kOverlappingCalls,
};

constexpr std::array<const char*, 9> kEventNames = {
    "configure",        "activate",   "activate_refused",        "io",
    "on_error",         "deactivate", "deactivate_while_moving", "io_while_inactive",
    "overlapping_calls"};

// Static so that it outlives the instance: tests read it after the daemon destroyed it.
struct Journal {
  std::array<std::atomic<std::uint8_t>, 128> events{};
  std::atomic<std::uint32_t> count{0};

  void clear() noexcept { count.store(0, std::memory_order_release); }
  void add(Event e) noexcept {
    const std::uint32_t n = count.load(std::memory_order_relaxed);
    if (n >= events.size()) return;
    events[n].store(static_cast<std::uint8_t>(e), std::memory_order_relaxed);
    count.store(n + 1, std::memory_order_release);
  }
};

Journal g_journal;
std::atomic<bool> g_fail_reads{false};
std::atomic<bool> g_refuse_activate{false};

class LifecycleHardware final : public Hardware {
 public:
  LifecycleHardware() { g_journal.clear(); }

  void configure(const PluginContext& ctx) override {
    const Guard guard(*this);
    ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
    params.finish();
    if (ctx.robot == nullptr || ctx.robot->drivetrain != DrivetrainKind::kDifferential) {
      throw ConfigError("lifecycle hardware: needs a differential robot model");
    }
    radius_left_m_ = ctx.robot->differential.wheel_radius_left_m;
    radius_right_m_ = ctx.robot->differential.wheel_radius_right_m;
    track_m_ = ctx.robot->differential.track_width_m;
    state_ = State::kInactive;
    g_journal.add(Event::kConfigure);
  }

  Status activate() override {
    const Guard guard(*this);
    if (g_refuse_activate.load(std::memory_order_acquire)) {
      g_journal.add(Event::kActivateRefused);
      error_ = "lifecycle: drives refused to enable (planted failure)";
      return Status::kError;
    }
    state_ = State::kActive;
    io_since_lifecycle_call_ = false;
    g_journal.add(Event::kActivate);
    return Status::kOk;
  }

  Status deactivate() override {
    const Guard guard(*this);
    const bool moving = rate_[0] != 0.0 || rate_[1] != 0.0;
    state_ = State::kInactive;
    g_journal.add(moving ? Event::kDeactivateWhileMoving : Event::kDeactivate);
    return Status::kOk;
  }

  void on_error(const char* /*cause*/) noexcept override {
    const Guard guard(*this);
    state_ = State::kError;
    io_since_lifecycle_call_ = false;
    g_journal.add(Event::kOnError);
  }

  Status read(double stamp_s, HardwareState& out) noexcept override {
    const Guard guard(*this);
    note_io();
    if (has_stamp_) {
      const double dt = stamp_s - stamp_s_;
      angle_[0] += rate_[0] * dt;
      angle_[1] += rate_[1] * dt;
    }
    stamp_s_ = stamp_s;
    has_stamp_ = true;
    if (g_fail_reads.load(std::memory_order_acquire)) {
      error_ = "lifecycle: injected read error";
      return Status::kError;
    }
    out = HardwareState{};
    out.stamp_s = stamp_s;
    out.module_count = 2;
    out.wheel_angle_rad[0] = angle_[0];
    out.wheel_angle_rad[1] = angle_[1];
    out.gyro_wz_radps = (radius_right_m_ * rate_[1] - radius_left_m_ * rate_[0]) / track_m_;
    out.gyro_valid = true;
    return Status::kOk;
  }

  Status write(const ActuatorCommand& command) noexcept override {
    const Guard guard(*this);
    note_io();
    rate_[0] = command.wheel_rate_radps[0];
    rate_[1] = command.wheel_rate_radps[1];
    return Status::kOk;
  }

  [[nodiscard]] const char* last_error() const noexcept override { return error_; }

 private:
  enum class State : std::uint8_t { kUnconfigured, kInactive, kActive, kError };

  // Two calls at once break the host's side of the lifecycle.
  struct Guard {
    explicit Guard(LifecycleHardware& h) noexcept : hardware(h) {
      if (hardware.calls_.fetch_add(1, std::memory_order_acq_rel) != 0) {
        g_journal.add(Event::kOverlappingCalls);
      }
    }
    ~Guard() { hardware.calls_.fetch_sub(1, std::memory_order_acq_rel); }
    Guard(const Guard&) = delete;
    Guard& operator=(const Guard&) = delete;
    LifecycleHardware& hardware;
  };

  void note_io() noexcept {
    if (state_ != State::kActive && state_ != State::kError) {
      g_journal.add(Event::kIoWhileInactive);
      return;
    }
    if (!io_since_lifecycle_call_) g_journal.add(Event::kIo);
    io_since_lifecycle_call_ = true;
  }

  std::atomic<int> calls_{0};
  State state_ = State::kUnconfigured;
  bool io_since_lifecycle_call_ = false;
  double radius_left_m_ = 0.0, radius_right_m_ = 0.0, track_m_ = 1.0;
  double angle_[2] = {0.0, 0.0};
  double rate_[2] = {0.0, 0.0};
  double stamp_s_ = 0.0;
  bool has_stamp_ = false;
  const char* error_ = "";
};

}  // namespace
}  // namespace swivel::test_plugins

extern "C" __attribute__((visibility("default"))) int swivel_lifecycle_journal(char* out,
                                                                               unsigned size) {
  using swivel::test_plugins::g_journal;
  using swivel::test_plugins::kEventNames;
  const std::uint32_t n = g_journal.count.load(std::memory_order_acquire);
  std::size_t used = 0;
  if (size > 0) out[0] = '\0';
  for (std::uint32_t i = 0; i < n; ++i) {
    const char* name = kEventNames[g_journal.events[i].load(std::memory_order_relaxed)];
    const std::size_t len = std::strlen(name) + (i > 0 ? 1 : 0);
    if (used + len + 1 > size) break;
    if (i > 0) out[used++] = ' ';
    std::memcpy(out + used, name, std::strlen(name) + 1);
    used += std::strlen(name);
  }
  return static_cast<int>(n);
}

extern "C" __attribute__((visibility("default"))) int swivel_lifecycle_set(const char* what,
                                                                           int on) {
  if (std::strcmp(what, "fail_reads") == 0) {
    swivel::test_plugins::g_fail_reads.store(on != 0, std::memory_order_release);
  } else if (std::strcmp(what, "refuse_activate") == 0) {
    swivel::test_plugins::g_refuse_activate.store(on != 0, std::memory_order_release);
  } else {
    return 1;
  }
  return 0;
}

SWIVEL_EXPORT_PLUGIN(swivel::test_plugins::LifecycleHardware, swivel::Hardware, "lifecycle")
