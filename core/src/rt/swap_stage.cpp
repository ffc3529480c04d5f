// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/swap_stage.hpp"

#include <time.h>

#include <cmath>

namespace swivel::rt {

bool at_rest(const StateSnapshot& last, bool last_write_zero, std::uint32_t module_count) noexcept {
  if (!last_write_zero || !last.has_joint_rates) return false;
  const Twist2& command = last.command_twist;
  if (command.vx_mps != 0.0 || command.vy_mps != 0.0 || command.wz_radps != 0.0) return false;
  for (std::uint32_t i = 0; i < module_count; ++i) {
    if (!(std::abs(last.wheel_rate_radps[i]) < kAtRestJointRateRadps) ||
        !(std::abs(last.steer_rate_radps[i]) < kAtRestJointRateRadps)) {
      return false;
    }
  }
  return true;
}

SwapStage::SwapStage(Localization& localization, const char* name) noexcept
    : active_(&localization) {
  copy_text(name, name_);
}

bool SwapStage::request(LoopSwap* swap) noexcept {
  if (swap == nullptr || swap->localization == nullptr) return false;
  bool idle = false;
  if (!in_flight_.compare_exchange_strong(idle, true, std::memory_order_acq_rel)) return false;
  swap->outcome = SwapOutcome{};
  pending_.store(swap, std::memory_order_release);
  return true;
}

LoopSwap* SwapStage::take_retired() noexcept {
  LoopSwap* retired = retired_.exchange(nullptr, std::memory_order_acq_rel);
  if (retired != nullptr) in_flight_.store(false, std::memory_order_release);
  return retired;
}

bool SwapStage::withdraw(LoopSwap* swap) noexcept {
  for (;;) {
    LoopSwap* expected = swap;
    if (pending_.compare_exchange_strong(expected, nullptr, std::memory_order_acq_rel)) {
      in_flight_.store(false, std::memory_order_release);
      return true;
    }
    if (retired_.load(std::memory_order_acquire) == swap ||
        !in_flight_.load(std::memory_order_acquire)) {
      return false;
    }
    // The loop is examining it at this very cycle boundary: it puts it back or retires it.
    const timespec pause{0, 20000};
    nanosleep(&pause, nullptr);
  }
}

bool SwapStage::request_localization(Localization* next, const char* name) noexcept {
  // The slot is the stage's own; it is free whenever no swap is in flight.
  if (next == nullptr || in_flight_.load(std::memory_order_acquire)) return false;
  localization_only_ = LoopSwap{};
  localization_only_.localization = next;
  copy_text(name, localization_only_.localization_name);
  return request(&localization_only_);
}

bool SwapStage::take(double now_s, bool at_rest, std::uint32_t module_count,
                     Drivetrain*& drivetrain, ModelSettings& model, PluginGuard& guard,
                     LoopEvents& events) noexcept {
  LoopSwap* swap = pending_.exchange(nullptr, std::memory_order_acq_rel);
  if (swap == nullptr) return false;
  if (swap->drivetrain != nullptr && !at_rest) {
    pending_.store(swap, std::memory_order_release);  // again next cycle, or withdrawn
    return false;
  }
  Localization* outgoing = active_.load(std::memory_order_relaxed);
  Localization* incoming = swap->localization;
  const PoseEstimate handed = outgoing->estimate();
  const char* thrown = nullptr;
  const char* refusal = nullptr;
  if (swap->drivetrain != nullptr && swap->drivetrain->module_count() != module_count) {
    refusal = "the new drivetrain drives a different number of modules";
  } else if (guard([&] { return incoming->hand_over(handed); }, thrown) != Status::kOk) {
    refusal = thrown != nullptr ? thrown : incoming->last_error();
    if (refusal == nullptr || refusal[0] == '\0') refusal = "hand_over failed without a reason";
  }
  if (refusal != nullptr) {
    // Roll back: the outgoing instances still hold a valid estimate and stay active; the
    // refused ones go back to the swapping thread. No fault: the robot lost nothing.
    swap->outcome.taken = false;
    copy_text(refusal, swap->outcome.refusal);
    retired_.store(swap, std::memory_order_release);
    events.log(LogLevel::kWarn, LogCode::kLocalizationSwapRefused, now_s, "",
               static_cast<double>(swaps_), 0.0, 0.0, 0.0, swap->outcome.refusal.data());
    return false;
  }
  swap->outcome.taken = true;
  swap->outcome.refusal[0] = '\0';
  active_.store(incoming, std::memory_order_release);
  swap->localization = outgoing;
  name_ = swap->localization_name;
  ++swaps_;
  const bool new_model = swap->drivetrain != nullptr;
  if (new_model) {
    Drivetrain* replaced = drivetrain;
    drivetrain = swap->drivetrain;
    swap->drivetrain = replaced;
    model = swap->model;
    ++model_swaps_;
    events.log(LogLevel::kInfo, LogCode::kMessage, now_s, "robot model swapped at rest",
               static_cast<double>(model_swaps_));
  }
  // request() refuses while a swap is in flight, so this slot is empty here.
  retired_.store(swap, std::memory_order_release);
  events.log(LogLevel::kInfo, LogCode::kLocalizationSwapped, now_s, "", static_cast<double>(swaps_),
             handed.pose.x_m, handed.pose.y_m, handed.pose.yaw_rad, name_.data());
  return new_model;
}

}  // namespace swivel::rt
