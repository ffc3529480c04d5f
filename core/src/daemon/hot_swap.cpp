// SPDX-License-Identifier: Apache-2.0
#include "hot_swap.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <thread>
#include <utility>

#include "swivel/clock.hpp"

namespace swivel::daemon {

HotSwap::HotSwap(PluginInstance<Localization> localization, PluginConfig& localization_slot,
                 PluginInstance<Drivetrain> drivetrain)
    : localization_(std::move(localization)),
      localization_slot_(localization_slot),
      drivetrain_(std::move(drivetrain)) {}

HotSwap::~HotSwap() = default;

// Destroys the incoming instances; no localization marks that none is in flight.
void HotSwap::release_incoming() noexcept {
  incoming_.localization.reset();
  incoming_.drivetrain.reset();
}

bool HotSwap::busy() const noexcept {
  return incoming_.localization || (loop_ != nullptr && loop_->swap_pending());
}

// Copying the slot may allocate: only std::bad_alloc can escape, which ends the process
// wherever it happens.
// NOLINTNEXTLINE(bugprone-exception-escape)
HotSwap::Result HotSwap::collect(std::string* refusal) noexcept {
  if (loop_ == nullptr || !incoming_.localization) return Result::kPending;
  const rt::LoopSwap* retired = loop_->take_retired_swap();
  if (retired == nullptr) return Result::kPending;
  if (retired == &request_ && !request_.outcome.taken &&
      request_.localization == incoming_.localization.get()) {
    // Rolled back: the loop kept the active instances and never used these.
    if (refusal != nullptr) *refusal = request_.outcome.refusal.data();
    release_incoming();
    return Result::kRefused;
  }
  if (retired == &request_ && request_.outcome.taken &&
      request_.localization == localization_.get() &&
      (!incoming_.drivetrain || request_.drivetrain == drivetrain_.get())) {
    // The loop let go of the outgoing instances: destroy them, then their libraries may
    // unload.
    localization_ = std::move(incoming_.localization);
    localization_slot_ = incoming_.localization_slot;
    if (incoming_.drivetrain) drivetrain_ = std::move(incoming_.drivetrain);
    release_incoming();
    return Result::kTaken;
  }
  try {
    spdlog::error("hot swap: the loop retired unexpected instances");
  } catch (...) {
  }
  return Result::kPending;
}

HotSwap::Result HotSwap::exchange(Incoming next, double timeout_s, std::string* refusal) {
  incoming_ = std::move(next);
  request_ = rt::LoopSwap{};
  request_.localization = incoming_.localization.get();
  rt::copy_text(incoming_.localization_slot.plugin.c_str(), request_.localization_name);
  request_.drivetrain = incoming_.drivetrain ? incoming_.drivetrain.get() : nullptr;
  request_.model = incoming_.model;
  if (!loop_->request_swap(&request_)) {
    release_incoming();
    throw PluginError("the loop refused the swap (one is still in flight)");
  }
  // The loop takes it, or rolls it back, at a cycle boundary (a model swap: one at rest).
  const double deadline_s = monotonic_s() + timeout_s;
  Result result = Result::kPending;
  while (result == Result::kPending && monotonic_s() < deadline_s) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    result = collect(refusal);
  }
  if (result == Result::kPending && request_.drivetrain != nullptr) {
    if (loop_->withdraw_swap(&request_)) {
      release_incoming();  // never called by the loop
      return Result::kNotAtRest;
    }
    result = collect(refusal);  // the loop decided just now
  }
  return result;
}

}  // namespace swivel::daemon
