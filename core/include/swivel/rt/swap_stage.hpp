// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's hot-swap stage: which localization (and, with a robot-model swap, which
// drivetrain) the loop uses, changed only at a cycle boundary. A swap is handed over through
// three atomic slots (requested, examined by the loop, let go) so that the swapping thread
// never waits on the loop except while withdrawing a swap the loop is examining at that very
// moment. The incoming localization's hand_over() with the outgoing estimate decides: kOk
// takes it and retires the outgoing instances, a refusal (or an exception) retires the
// incoming ones and keeps the rest; no fault latches. A swap with a new drivetrain waits for
// a cycle at rest, so that setpoints never change kinematics mid-motion.
//
// One swapping thread calls request(), take_retired(), withdraw(); the loop thread take() and
// publish(); any thread active() and pending(). Real-time safe (withdraw() excepted: it may
// sleep through a cycle boundary): no allocation, no lock; noexcept.

#include <atomic>
#include <cstdint>

#include "swivel/motion/twist_limiter.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/rt/loop_events.hpp"
#include "swivel/rt/plugin_guard.hpp"
#include "swivel/rt/state_snapshot.hpp"

namespace swivel::rt {

/// The robot model's share of the loop's settings: what a model swap replaces.
struct ModelSettings {
  MotionLimits limits;  ///< LoopOptions::limits
  double wheel_encoder_resolution_rad = 0.0;
  double steer_encoder_resolution_rad = 0.0;
};

/// How a hot swap the loop took ended (ControlLoop::take_retired_localization()).
struct SwapOutcome {
  /// True: the incoming instance became active and the outgoing one was retired. False: the
  /// incoming one refused the hand-over, the outgoing one stays active and the incoming one
  /// was retired instead.
  bool taken = true;
  FaultDetail refusal{};  ///< why it refused: its last_error() or the loop's text
};

/// A hot swap handed to the loop with request_swap(): a new localization and, for a new
/// robot model, a new drivetrain with the model's loop settings. The requester owns it and
/// leaves it alone from request_swap() until take_retired_swap() or withdraw_swap() gives it
/// back. The loop writes into it what it let go of: after a taken swap the pointers hold the
/// outgoing instances, after a refused one still the incoming ones (`outcome` says which).
struct LoopSwap {
  Localization* localization = nullptr;  ///< configured and reset off the loop; never null
  ShortName localization_name{};
  /// Configured for the new model off the loop, with as many modules as the running one;
  /// null keeps the running drivetrain and `model` is ignored. Taken only at rest.
  Drivetrain* drivetrain = nullptr;
  ModelSettings model;
  SwapOutcome outcome;  ///< written by the loop when it lets go of the swap
};

/// Below this every wheel and steering rate measured over the twist window, rad/s, counts
/// as at rest for a robot-model swap (3.75 mm/s on a 75 mm wheel).
inline constexpr double kAtRestJointRateRadps = 0.1;

/// At rest after the cycle that published `last`: it commanded zero, the last setpoints
/// written were zero (`last_write_zero`), and the encoders measured every wheel and steering
/// rate of its `module_count` modules below kAtRestJointRateRadps (no measurement, e.g. after
/// a failed reading, is not at rest). A running calibration is the caller's to exclude.
bool at_rest(const StateSnapshot& last, bool last_write_zero, std::uint32_t module_count) noexcept;

class SwapStage {
 public:
  /// `localization` is active from the start; `name` is copied (truncated).
  SwapStage(Localization& localization, const char* name) noexcept;

  /// The swapping thread (ControlLoop::request_swap()).
  bool request(LoopSwap* swap) noexcept;
  /// The swapping thread (ControlLoop::take_retired_swap()).
  LoopSwap* take_retired() noexcept;
  /// The swapping thread (ControlLoop::withdraw_swap()). Not real-time safe.
  bool withdraw(LoopSwap* swap) noexcept;
  /// The swapping thread (ControlLoop::request_localization_swap()).
  bool request_localization(Localization* next, const char* name) noexcept;

  /// Any thread. True while a requested swap has not been taken, refused or withdrawn.
  [[nodiscard]] bool pending() const noexcept {
    return in_flight_.load(std::memory_order_acquire) &&
           retired_.load(std::memory_order_acquire) == nullptr;
  }
  /// Any thread. The localization in use.
  [[nodiscard]] Localization* active() const noexcept {
    return active_.load(std::memory_order_acquire);
  }

  /// Loop thread, at the cycle boundary: takes or refuses a pending swap (one with a drivetrain
  /// only when `at_rest`, else it waits). A taken model swap replaces `drivetrain`, copies the
  /// model into `model` and returns true: the caller applies it.
  bool take(double now_s, bool at_rest, std::uint32_t module_count, Drivetrain*& drivetrain,
            ModelSettings& model, PluginGuard& guard, LoopEvents& events) noexcept;

  /// Loop thread: the active plugin's name and the swap counts into the snapshot.
  void publish(StateSnapshot& state) const noexcept {
    state.localization_plugin = name_;
    state.localization_swaps = swaps_;
    state.model_swaps = model_swaps_;
  }

 private:
  std::atomic<Localization*> active_;
  // A swap in flight: requested (pending), examined by the loop (neither), let go (retired).
  std::atomic<bool> in_flight_{false};  // from request() until given back
  std::atomic<LoopSwap*> pending_{nullptr};
  std::atomic<LoopSwap*> retired_{nullptr};
  LoopSwap localization_only_{};  // request_localization()'s
  // Loop thread.
  ShortName name_{};
  std::uint64_t swaps_ = 0;
  std::uint64_t model_swaps_ = 0;
};

}  // namespace swivel::rt
