// SPDX-License-Identifier: Apache-2.0
#include "script_source.hpp"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <utility>

#include "swivel/clock.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {

ScriptCommandSource::ScriptCommandSource(rt::ControlLoop& loop, std::vector<ScriptStep> script,
                                         double start_s)
    : loop_(loop), script_(std::move(script)), start_s_(start_s) {
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

void ScriptCommandSource::stop() noexcept {
  if (thread_.joinable()) {
    thread_.request_stop();
    thread_.join();
  }
}

void ScriptCommandSource::run(const std::stop_token& stop) {
  constexpr double kPushPeriodS = 0.02;  // 50 Hz: well inside any sensible command timeout
  double total_s = 0.0;
  for (const auto& step : script_) total_s += step.duration_s;
  std::mutex mutex;
  std::condition_variable_any wake;
  std::uint64_t sequence = 0;
  std::unique_lock lock(mutex);
  while (!stop.stop_requested()) {
    const double now = monotonic_s();
    double into_s = std::fmod(now - start_s_, total_s);
    std::size_t i = 0;
    while (i + 1 < script_.size() && into_s >= script_[i].duration_s) {
      into_s -= script_[i].duration_s;
      ++i;
    }
    VelocityCommand command;
    command.twist = script_[i].twist;
    command.received_s = now;
    command.sequence = ++sequence;
    loop_.push_command(command);
    wake.wait_for(lock, stop, std::chrono::duration<double>(kPushPeriodS), [] { return false; });
  }
}

}  // namespace swivel::daemon
