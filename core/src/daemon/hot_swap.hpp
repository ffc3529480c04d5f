// SPDX-License-Identifier: Apache-2.0
#pragma once
// The localization instance the real-time loop uses and a hot swap in flight: hands a new
// instance to the loop, learns whether the loop took it or rolled it back, and destroys
// whichever instance the loop let go of, off the loop (docs/architecture.md "Reload and hot swap").
//
// Main thread only (reloads and the main loop's periodic collection). Not real-time safe.

#include <string>

#include "swivel/daemon/daemon_config.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/plugin_loader.hpp"

namespace swivel::rt {
class ControlLoop;
}

namespace swivel::daemon {

class LocalizationSwap {
 public:
  /// What the loop did with the instance handed over, once it let go of one.
  enum class Result { kPending, kTaken, kRefused };

  /// `active` is the instance the loop starts with; `active_slot` its configuration, which
  /// is overwritten with the incoming one's when the loop takes a swap.
  LocalizationSwap(PluginInstance<Localization> active, PluginConfig& active_slot);
  ~LocalizationSwap();
  LocalizationSwap(const LocalizationSwap&) = delete;
  LocalizationSwap& operator=(const LocalizationSwap&) = delete;

  /// The instance the loop uses (or, during a swap, used before it).
  [[nodiscard]] Localization& active() { return *active_; }

  /// Once the loop runs: attach it (before any other call). Null detaches (after it stopped).
  void attach(rt::ControlLoop* loop) noexcept { loop_ = loop; }

  /// Takes back the instance the loop let go of, if it did: the outgoing one after a taken
  /// swap (destroyed; the incoming one becomes active), or the incoming one after a refused
  /// hand-over (destroyed; `refusal`, when given, receives the plugin's reason).
  Result collect(std::string* refusal = nullptr) noexcept;

  /// True while an earlier swap has not been taken or rolled back.
  [[nodiscard]] bool busy() const noexcept;

  /// Hands `next` (configured and reset) with its configuration `slot` to the loop and
  /// waits up to `timeout_s` for the loop to take it or roll it back at a cycle boundary.
  /// kPending when the loop has not decided yet (collect() later finishes the swap).
  /// @throws PluginError when the loop refuses the request (a swap is still pending).
  Result swap(PluginInstance<Localization> next, const PluginConfig& slot, double timeout_s,
              std::string* refusal);

  /// Destroys an instance handed over that the loop never took (after the loop stopped).
  void drop_incoming() noexcept { incoming_.reset(); }

 private:
  PluginInstance<Localization> active_;
  PluginConfig& active_slot_;
  // Handed to the loop and not retired or taken yet; `incoming_slot_` is its configuration.
  PluginInstance<Localization> incoming_;
  PluginConfig incoming_slot_;
  rt::ControlLoop* loop_ = nullptr;
};

}  // namespace swivel::daemon
