// SPDX-License-Identifier: Apache-2.0
#pragma once
// `swiveld --record`: records the live run as a run log (swivel/run_log.hpp), one row per
// new loop state at the recording rate, from its own thread; flushed every second and at
// the end.

#include <memory>
#include <string>
#include <thread>

#include "swivel/robot_model.hpp"
#include "swivel/run_log.hpp"

namespace swivel::rt {
class ControlLoop;
}

namespace swivel::daemon {

class RunRecorder {
 public:
  /// Creates the file and writes its header (before anything runs, so that a path that
  /// cannot be written stops the start-up). `config_file` is named in a header comment.
  /// @throws RunLogError when the file cannot be created.
  RunRecorder(std::string path, double rate_hz, const RobotModel& robot,
              const std::string& config_file);
  /// Stops the thread and flushes the file (a failure is logged).
  ~RunRecorder();
  RunRecorder(const RunRecorder&) = delete;
  RunRecorder& operator=(const RunRecorder&) = delete;

  /// Starts recording the states of `loop`, which must outlive stop().
  void start(const rt::ControlLoop& loop);
  /// Stops and joins the thread. Idempotent.
  void stop() noexcept;

  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  void run(const std::stop_token& stop, const rt::ControlLoop& loop);
  void flush() noexcept;

  std::string path_;
  double rate_hz_;
  bool differential_;
  std::size_t modules_;
  std::unique_ptr<RunLogWriter> writer_;
  std::jthread thread_;
};

}  // namespace swivel::daemon
