// SPDX-License-Identifier: Apache-2.0
#include "run_recorder.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <utility>

#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {

RunRecorder::RunRecorder(std::string path, double rate_hz, const RobotModel& robot,
                         const std::string& config_file)
    : path_(std::move(path)),
      rate_hz_(rate_hz),
      differential_(robot.drivetrain == DrivetrainKind::kDifferential),
      modules_(robot.module_count()) {
  RunLogHeader header = run_log_header(robot);
  header.comments.push_back("recorded by swiveld from " + config_file + " at " +
                            std::to_string(rate_hz) + " Hz");
  // The truth columns hold only the hardware's own ground truth (Hardware::ground_truth: a
  // simulation's pose of the robot's reference point, read in the same cycle), never an
  // external motion capture: the model-gap workflow need not fit a clock offset or a tracked
  // body's lever arm and yaw offset for it.
  header.comments.emplace_back("truth_clock: shared");
  header.comments.emplace_back("truth_frame: robot");
  writer_ = std::make_unique<RunLogWriter>(path_, header);
}

RunRecorder::~RunRecorder() {
  stop();
  flush();
}

void RunRecorder::start(const rt::ControlLoop& loop) {
  thread_ = std::jthread([this, &loop](const std::stop_token& stop) { run(stop, loop); });
}

void RunRecorder::stop() noexcept {
  if (thread_.joinable()) {
    thread_.request_stop();
    thread_.join();
  }
}

void RunRecorder::flush() noexcept {
  try {
    writer_->flush();
  } catch (const std::exception& e) {
    try {
      spdlog::error("{}", e.what());
    } catch (...) {
    }
  }
}

void RunRecorder::run(const std::stop_token& stop, const rt::ControlLoop& loop) {
  const auto period = std::chrono::duration<double>(1.0 / rate_hz_);
  std::uint64_t last_cycle = 0;
  double t0 = -1.0;
  auto next = std::chrono::steady_clock::now();
  auto next_flush = next + std::chrono::seconds(1);
  std::mutex mutex;
  std::condition_variable_any wake;
  std::unique_lock lock(mutex);
  while (!stop.stop_requested()) {
    const StateSnapshot s = loop.latest();
    if (s.cycle > last_cycle) {
      last_cycle = s.cycle;
      if (t0 < 0.0) t0 = s.stamp_s;
      RunLogSample row;
      row.t_s = s.stamp_s - t0;
      row.cmd = s.command_twist;
      for (std::size_t i = 0; i < modules_ && i < kMaxModules; ++i) {
        row.wheel_rad[i] = s.wheel_angle_rad[i];
        if (!differential_) row.steer_rad[i] = s.steer_angle_rad[i];
      }
      row.gyro_wz_radps = s.gyro_wz_radps;
      row.has_truth = s.has_truth;
      row.truth = s.truth;
      try {
        writer_->write(row);
        if (std::chrono::steady_clock::now() >= next_flush) {
          writer_->flush();
          next_flush += std::chrono::seconds(1);
        }
      } catch (const std::exception& e) {
        spdlog::error("run log {}: {}; recording stopped", path_, e.what());
        return;
      }
    }
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    wake.wait_until(lock, stop, next, [] { return false; });
  }
}

}  // namespace swivel::daemon
