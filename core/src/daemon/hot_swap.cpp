// SPDX-License-Identifier: Apache-2.0
#include "localization_swap.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <thread>
#include <utility>

#include "swivel/clock.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {

LocalizationSwap::LocalizationSwap(PluginInstance<Localization> active, PluginConfig& active_slot)
    : active_(std::move(active)), active_slot_(active_slot) {}

LocalizationSwap::~LocalizationSwap() = default;

bool LocalizationSwap::busy() const noexcept {
  return incoming_ || (loop_ != nullptr && loop_->swap_pending());
}

LocalizationSwap::Result LocalizationSwap::collect(std::string* refusal) noexcept {
  if (loop_ == nullptr || !incoming_) return Result::kPending;
  rt::SwapOutcome outcome;
  Localization* retired = loop_->take_retired_localization(&outcome);
  if (retired == nullptr) return Result::kPending;
  if (!outcome.taken && retired == incoming_.get()) {
    // Rolled back: the loop kept the active instance and never used this one.
    if (refusal != nullptr) *refusal = outcome.refusal.data();
    incoming_.reset();
    return Result::kRefused;
  }
  if (outcome.taken && retired == active_.get()) {
    // The loop let go of the outgoing instance: destroy it, then its library may unload.
    active_ = std::move(incoming_);
    active_slot_ = incoming_slot_;
    return Result::kTaken;
  }
  try {
    spdlog::error("hot swap: the loop retired an unexpected localization instance");
  } catch (...) {
  }
  return Result::kPending;
}

LocalizationSwap::Result LocalizationSwap::swap(PluginInstance<Localization> next,
                                                const PluginConfig& slot, double timeout_s,
                                                std::string* refusal) {
  incoming_ = std::move(next);
  incoming_slot_ = slot;
  if (!loop_->request_localization_swap(incoming_.get(), slot.plugin.c_str())) {
    incoming_.reset();
    throw PluginError("the loop refused the localization swap (one is still pending)");
  }
  // The loop takes it, or rolls it back, at its next cycle boundary.
  const double deadline_s = monotonic_s() + timeout_s;
  Result result = Result::kPending;
  while (result == Result::kPending && monotonic_s() < deadline_s) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    result = collect(refusal);
  }
  return result;
}

}  // namespace swivel::daemon
