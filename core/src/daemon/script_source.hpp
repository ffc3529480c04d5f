// SPDX-License-Identifier: Apache-2.0
#pragma once
// The built-in command source (`command.source: script`): a thread that plays the
// configuration's motion script in a loop, pushing the step in force to the real-time loop
// at 50 Hz (well inside any sensible command timeout). The loop's only command producer
// while it runs (DDS velocity commands are ignored then).

#include <thread>
#include <vector>

#include "swivel/daemon/daemon_config.hpp"

namespace swivel::rt {
class ControlLoop;
}

namespace swivel::daemon {

class ScriptCommandSource {
 public:
  /// Starts the thread. The script (non-empty, every step with a positive duration) starts
  /// at `start_s` (the loop's clock); `loop` must outlive this.
  ScriptCommandSource(rt::ControlLoop& loop, std::vector<ScriptStep> script, double start_s);
  /// Stops and joins the thread.
  ~ScriptCommandSource() { stop(); }
  ScriptCommandSource(const ScriptCommandSource&) = delete;
  ScriptCommandSource& operator=(const ScriptCommandSource&) = delete;

  /// No more commands after this returns. Idempotent.
  void stop() noexcept;

 private:
  void run(const std::stop_token& stop);

  rt::ControlLoop& loop_;
  std::vector<ScriptStep> script_;
  double start_s_;
  std::jthread thread_;
};

}  // namespace swivel::daemon
