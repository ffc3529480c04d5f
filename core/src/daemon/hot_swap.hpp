// SPDX-License-Identifier: Apache-2.0
#pragma once
// The drivetrain and localization instances the real-time loop uses and a hot swap in flight:
// hands new instances to the loop (a localization, or for a new robot model a drivetrain
// and a localization built for it), learns whether the loop took them or rolled them back,
// and destroys whichever instances the loop let go of, off the loop (docs/architecture.md
// "Reload and hot swap").
//
// Main thread only (reloads and the main loop's periodic collection). Not real-time safe.

#include <string>

#include "swivel/daemon/daemon_config.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/plugin_loader.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {

class HotSwap {
 public:
  /// What the loop did with the instances handed over. kNotAtRest: a new robot model that
  /// the loop did not take because the robot did not come to rest in time; it was withdrawn.
  enum class Result { kPending, kTaken, kRefused, kNotAtRest };

  /// What a swap brings: a localization with its configuration and, for a new robot model,
  /// a drivetrain configured for it with the model's loop settings.
  // NOLINTNEXTLINE(bugprone-exception-escape): YAML::Node moves by copying, which may allocate
  struct Incoming {
    PluginInstance<Localization> localization;  ///< configured and reset
    PluginConfig localization_slot;
    PluginInstance<Drivetrain> drivetrain;  ///< empty: the running drivetrain stays
    rt::ModelSettings model;                ///< with a drivetrain only
  };

  /// `localization` and `drivetrain` are the instances the loop starts with;
  /// `localization_slot` the localization's configuration, which is overwritten with the
  /// incoming one's when the loop takes a swap.
  HotSwap(PluginInstance<Localization> localization, PluginConfig& localization_slot,
          PluginInstance<Drivetrain> drivetrain);
  ~HotSwap();
  HotSwap(const HotSwap&) = delete;
  HotSwap& operator=(const HotSwap&) = delete;

  /// The instances the loop uses (or, during a swap, used before it).
  [[nodiscard]] Localization& localization() { return *localization_; }
  [[nodiscard]] Drivetrain& drivetrain() { return *drivetrain_; }

  /// Once the loop runs: attach it (before any other call). Null detaches (after it stopped).
  void attach(rt::ControlLoop* loop) noexcept { loop_ = loop; }

  /// Takes back the instances the loop let go of, if it did: the outgoing ones after a taken
  /// swap (destroyed; the incoming ones become active), or the incoming ones after a refused
  /// hand-over (destroyed; `refusal`, when given, receives the reason).
  Result collect(std::string* refusal = nullptr) noexcept;  // NOLINT(bugprone-exception-escape)

  /// True while an earlier swap has not been taken or rolled back.
  [[nodiscard]] bool busy() const noexcept;

  /// Hands `next` to the loop and waits up to `timeout_s` for the loop to take it or roll it
  /// back at a cycle boundary. A localization alone: kPending when the loop has not decided
  /// yet (collect() later finishes the swap). With a drivetrain the loop waits for a cycle
  /// at rest; when none came within `timeout_s` the swap is withdrawn and destroyed
  /// (kNotAtRest), so that a model swap has always ended when this returns.
  /// @throws PluginError when the loop refuses the request (a swap is still in flight).
  Result exchange(Incoming next, double timeout_s, std::string* refusal);

  /// Destroys instances handed over that the loop never took (after the loop stopped).
  void drop_incoming() noexcept { release_incoming(); }

 private:
  void release_incoming() noexcept;

  PluginInstance<Localization> localization_;
  PluginConfig& localization_slot_;
  PluginInstance<Drivetrain> drivetrain_;
  // Handed to the loop and not retired or taken yet (no localization: none in flight), and
  // the request the loop reads and writes back into meanwhile.
  Incoming incoming_;
  rt::LoopSwap request_;
  rt::ControlLoop* loop_ = nullptr;
};

}  // namespace swivel::daemon
