// SPDX-License-Identifier: Apache-2.0
#include "swivel/dds/run_sample_publisher.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "swivel.h"
#include "swivel/clock.hpp"
#include "swivel/dds/topics.hpp"

namespace swivel::dds {

RunSamplePublisher::RunSamplePublisher(dds_entity_t participant, std::string robot_id,
                                       DrivetrainKind drivetrain, double period_s, TakeSample take)
    : robot_id_(std::move(robot_id)),
      drivetrain_(drivetrain),
      period_s_(period_s),
      take_(std::move(take)) {
  if (robot_id_.empty()) throw std::invalid_argument("RunSamplePublisher: empty robot id");
  if (!take_) throw std::invalid_argument("RunSamplePublisher: no sample source");
  if (!std::isfinite(period_s_) || !(period_s_ > 0.0)) {
    throw std::invalid_argument("RunSamplePublisher: period_s must be finite and positive");
  }
  const dds_entity_t topic =
      create_topic(participant, &swivel_msg_RunSample_desc, kRunSamplesTopic);
  const QosPtr qos = run_samples_qos();
  writer_ = check(dds_create_writer(participant, topic, qos.get(), nullptr),
                  "dds_create_writer(swivel_run_samples)");
}

RunSamplePublisher::~RunSamplePublisher() { stop(); }

void RunSamplePublisher::start() {
  if (thread_.joinable()) throw std::logic_error("RunSamplePublisher::start called twice");
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

void RunSamplePublisher::stop() noexcept {
  if (!thread_.joinable()) return;
  thread_.request_stop();
  thread_.join();
  // Reliable readers are resent what they missed only while the writer exists.
  (void)dds_wait_for_acks(writer_, DDS_SECS(1));
}

RunSampleCounters RunSamplePublisher::counters() const {
  return {published_.load(), lost_at_source_.load(), write_failures_.load()};
}

void RunSamplePublisher::run(const std::stop_token& stop) {
  // Several looks per sample period keep the loop's ring nearly empty; bounded so that a
  // slow rate still shows samples promptly and a fast one does not spin.
  const auto wait = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(std::clamp(period_s_ / 4.0, 0.001, 0.02)));
  while (!stop.stop_requested()) {
    drain();
    std::this_thread::sleep_for(wait);
  }
  drain();  // what the loop's last cycles left
}

void RunSamplePublisher::drain() {
  RunSample sample;
  while (take_(sample)) publish(sample);
}

void RunSamplePublisher::publish(const RunSample& r) {
  if (r.sequence > last_sequence_ + 1) {
    const std::uint64_t lost = r.sequence - last_sequence_ - 1;
    lost_at_source_.fetch_add(lost, std::memory_order_relaxed);
    // At most one warning a second: a machine too loaded to keep up would flood the log.
    if (monotonic_s() >= next_loss_warning_s_) {
      next_loss_warning_s_ = monotonic_s() + 1.0;
      spdlog::warn(
          "dds: {}: {} run sample(s) before #{} lost: the loop's ring was full (this "
          "publisher fell behind); {} lost so far",
          kRunSamplesTopic, lost, r.sequence, lost_at_source_.load(std::memory_order_relaxed));
    }
  }
  last_sequence_ = r.sequence;

  const auto modules =
      static_cast<std::uint32_t>(std::min<std::size_t>(r.module_count, kMaxModules));
  const bool swpc = drivetrain_ == DrivetrainKind::kSwpc;
  // The sequences point into the sample's own arrays (written, never freed by DDS).
  std::array<double, kMaxModules> wheels = r.wheel_angle_rad;
  std::array<double, kMaxModules> steers = r.steer_angle_rad;
  swivel_msg_RunSample msg{};
  msg.robot_id = robot_id_.data();
  msg.sequence_number = r.sequence;
  msg.cycle = r.cycle;
  msg.stamp_s = r.stamp_s;
  msg.drivetrain = swpc ? swivel_msg_DRIVETRAIN_SWPC : swivel_msg_DRIVETRAIN_DIFFERENTIAL;
  msg.module_count = modules;
  msg.cmd_vx_mps = r.command_twist.vx_mps;
  msg.cmd_vy_mps = r.command_twist.vy_mps;
  msg.cmd_wz_radps = r.command_twist.wz_radps;
  // The sequence lends `values` to Cyclone, whose C type holds a non-const pointer.
  // NOLINTNEXTLINE(readability-non-const-parameter)
  const auto borrow = [](auto& sequence, double* values, std::uint32_t length) {
    sequence._maximum = length;
    sequence._length = length;
    sequence._buffer = values;
    sequence._release = false;
  };
  borrow(msg.wheel_angle_rad, wheels.data(), modules);
  borrow(msg.steer_angle_rad, steers.data(), swpc ? modules : 0U);
  msg.gyro_wz_radps = r.gyro_wz_radps;
  msg.has_truth = r.has_truth;
  msg.truth_x_m = r.truth.x_m;
  msg.truth_y_m = r.truth.y_m;
  msg.truth_yaw_rad = r.truth.yaw_rad;
  msg.truth_stamp_s = r.truth_stamp_s;
  msg.est_x_m = r.estimate.x_m;
  msg.est_y_m = r.estimate.y_m;
  msg.est_yaw_rad = r.estimate.yaw_rad;
  msg.fault_code = static_cast<std::uint16_t>(r.fault);
  switch (r.mode) {
    case LoopMode::kIdle: msg.mode = swivel_msg_LOOP_MODE_IDLE; break;
    case LoopMode::kVelocity: msg.mode = swivel_msg_LOOP_MODE_VELOCITY; break;
    case LoopMode::kCalibration: msg.mode = swivel_msg_LOOP_MODE_CALIBRATION; break;
    case LoopMode::kSafeStop: msg.mode = swivel_msg_LOOP_MODE_SAFE_STOP; break;
  }
  const dds_return_t rc = dds_write(writer_, &msg);
  if (rc < 0) {
    write_failures_.fetch_add(1, std::memory_order_relaxed);
    if (!warned_write_) {
      warned_write_ = true;
      spdlog::warn(
          "dds: {}: dds_write failed ({}); a recorder sees the gap, further failures "
          "are counted",
          kRunSamplesTopic, dds_strretcode(rc));
    }
    return;
  }
  published_.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace swivel::dds
