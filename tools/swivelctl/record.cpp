// SPDX-License-Identifier: Apache-2.0
#include "record.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "client.hpp"
#include "swivel.h"
#include "swivel/dds/topics.hpp"
#include "swivel/run_log.hpp"

namespace swivel::ctl {
namespace {

using Seconds = std::chrono::duration<double>;
using SteadyClock = std::chrono::steady_clock;

struct RecordOptions {
  std::string out;
  double duration_s = 0.0;  // 0: until Ctrl-C
  std::string robot;
  double timeout_s = 3.0;
  std::uint32_t domain_id = 0;
};

std::string fixed(double value, int decimals) {
  std::array<char, 64> text{};
  (void)std::snprintf(text.data(), text.size(), "%.*f", decimals, value);
  return text.data();
}

bool finite_sample(const swivel_msg_RunSample& m) {
  bool ok = std::isfinite(m.stamp_s) && std::isfinite(m.cmd_vx_mps) &&
            std::isfinite(m.cmd_vy_mps) && std::isfinite(m.cmd_wz_radps) &&
            std::isfinite(m.gyro_wz_radps) && std::isfinite(m.est_x_m) &&
            std::isfinite(m.est_y_m) && std::isfinite(m.est_yaw_rad);
  if (m.has_truth) {
    ok = ok && std::isfinite(m.truth_x_m) && std::isfinite(m.truth_y_m) &&
         std::isfinite(m.truth_yaw_rad);
  }
  for (std::uint32_t i = 0; ok && i < m.wheel_angle_rad._length; ++i) {
    ok = std::isfinite(m.wheel_angle_rad._buffer[i]);
  }
  for (std::uint32_t i = 0; ok && i < m.steer_angle_rad._length; ++i) {
    ok = std::isfinite(m.steer_angle_rad._buffer[i]);
  }
  return ok;
}

// A running daemon's run samples into one run log. Samples that cannot be rows (a non-finite
// reading in a fault cycle, a malformed sample) are skipped and counted; a jump in the
// sequence numbers is a gap; anything that would make the log inconsistent ends it.
class Recording {
 public:
  Recording(const RecordOptions& options, std::string robot)
      : options_(options), robot_(std::move(robot)) {}

  enum class Outcome { kContinue, kDone, kFailed };

  Outcome add(const swivel_msg_RunSample& m) {
    const DrivetrainKind drivetrain = m.drivetrain == swivel_msg_DRIVETRAIN_SWPC
                                          ? DrivetrainKind::kSwpc
                                          : DrivetrainKind::kDifferential;
    if (!writer_) {
      RunLogHeader header;
      header.robot = robot_;
      header.drivetrain = drivetrain;
      header.module_count = m.module_count;
      header.estimate_columns = true;
      header.comments.push_back("recorded by swivelctl record from " + robot_ + " over DDS (" +
                                dds::kRunSamplesTopic + ")");
      try {
        writer_ = std::make_unique<RunLogWriter>(options_.out, header);
      } catch (const RunLogError& e) {
        std::cerr << "swivelctl: cannot record " << robot_ << ": " << e.what() << '\n';
        return Outcome::kFailed;
      }
      first_stamp_s_ = m.stamp_s;
      last_sequence_ = m.sequence_number - 1;  // the first sample is no gap
      if (m.cmd_vx_mps != 0.0 || m.cmd_vy_mps != 0.0 || m.cmd_wz_radps != 0.0) {
        // The gap workflow's command replay starts from rest.
        std::cerr << "swivelctl: note: " << robot_
                  << " is moving as the recording starts; for swivel-lab gap, start recording "
                     "with the robot at rest\n";
      }
    }
    const RunLogHeader& header = writer_->header();
    if (drivetrain != header.drivetrain || m.module_count != header.module_count) {
      std::cerr << "swivelctl: " << robot_ << " changed its drivetrain or module count ("
                << m.module_count << " modules now, " << header.module_count
                << " before): the daemon restarted with another robot; recording ends\n";
      return Outcome::kFailed;
    }
    if (m.sequence_number <= last_sequence_) {
      if (m.sequence_number == last_sequence_) return Outcome::kContinue;  // a duplicate
      std::cerr << "swivelctl: " << robot_ << "'s run sample sequence went back from "
                << last_sequence_ << " to " << m.sequence_number
                << ": the daemon restarted, or two daemons run as this robot; recording ends\n";
      return Outcome::kFailed;
    }
    // Counted before the duration check: samples missing before the one that ends the
    // recording may belong to the recorded window.
    if (m.sequence_number > last_sequence_ + 1) {
      ++gaps_;
      missing_ += m.sequence_number - last_sequence_ - 1;
    }
    last_sequence_ = m.sequence_number;

    const double t_s = m.stamp_s - first_stamp_s_;
    if (options_.duration_s > 0.0 && t_s >= options_.duration_s) return Outcome::kDone;
    const std::uint32_t steering = drivetrain == DrivetrainKind::kSwpc ? m.module_count : 0;
    if (m.wheel_angle_rad._length != m.module_count || m.steer_angle_rad._length != steering ||
        !finite_sample(m) || (rows_ > 0 && t_s < last_t_s_)) {
      ++skipped_;
      return Outcome::kContinue;
    }
    RunLogSample row;
    row.t_s = t_s;
    row.cmd = {m.cmd_vx_mps, m.cmd_vy_mps, m.cmd_wz_radps};
    for (std::uint32_t i = 0; i < m.module_count; ++i) {
      row.wheel_rad[i] = m.wheel_angle_rad._buffer[i];
    }
    for (std::uint32_t i = 0; i < steering; ++i) row.steer_rad[i] = m.steer_angle_rad._buffer[i];
    row.gyro_wz_radps = m.gyro_wz_radps;
    row.has_truth = m.has_truth;
    row.truth = {m.truth_x_m, m.truth_y_m, m.truth_yaw_rad};
    row.estimate = {m.est_x_m, m.est_y_m, m.est_yaw_rad};
    row.fault_code = m.fault_code;
    writer_->write(row);
    ++rows_;
    last_t_s_ = t_s;
    return Outcome::kContinue;
  }

  void flush() {
    if (writer_) writer_->flush();
  }
  [[nodiscard]] bool started() const { return writer_ != nullptr; }

  [[nodiscard]] std::string progress() const {
    return robot_ + ": " + std::to_string(rows_) + " rows, " + fixed(last_t_s_, 2) + " s, " +
           std::to_string(gaps_) + " gaps (" + std::to_string(missing_) + " samples missing), " +
           std::to_string(skipped_) + " skipped";
  }

  [[nodiscard]] std::string summary() const {
    const double rate_hz = rows_ > 1 ? static_cast<double>(rows_ - 1) / last_t_s_ : 0.0;
    return "recorded " + std::to_string(rows_) + " rows (" + fixed(last_t_s_, 2) + " s at " +
           fixed(rate_hz, 1) + " Hz) from " + robot_ + " to " + options_.out + ": " +
           std::to_string(gaps_) + " gaps (" + std::to_string(missing_) + " samples missing), " +
           std::to_string(skipped_) + " skipped";
  }

 private:
  const RecordOptions& options_;
  std::string robot_;
  std::unique_ptr<RunLogWriter> writer_;
  double first_stamp_s_ = 0.0;
  double last_t_s_ = 0.0;
  std::uint64_t last_sequence_ = 0;
  std::uint64_t rows_ = 0;
  std::uint64_t gaps_ = 0;
  std::uint64_t missing_ = 0;
  std::uint64_t skipped_ = 0;
};

int run_record(const RecordOptions& options) {
  // A path that cannot be written is reported before anything waits on the network.
  if (!std::ofstream(options.out, std::ios::out | std::ios::trunc)) {
    std::cerr << "swivelctl: " << options.out << ": cannot open for writing\n";
    return 1;
  }
  Client client(options.domain_id);
  // Created first, so that it matches the daemon's writer while the robot is resolved.
  const dds::QosPtr qos = dds::run_samples_qos();
  const dds_entity_t reader =
      client.reader(&swivel_msg_RunSample_desc, dds::kRunSamplesTopic, qos.get());
  const Seconds timeout(options.timeout_s);
  std::string robot;
  try {
    robot = resolve_robot(client, options.robot, timeout);
  } catch (...) {
    (void)std::remove(options.out.c_str());
    throw;
  }

  Recording recording(options, robot);
  auto last_sample = SteadyClock::now();
  auto next_progress = SteadyClock::now() + std::chrono::seconds(1);
  Recording::Outcome outcome = Recording::Outcome::kContinue;
  bool stalled = false;
  while (outcome == Recording::Outcome::kContinue && !interrupted()) {
    if (SteadyClock::now() - last_sample > timeout) {
      stalled = true;
      break;
    }
    if (!client.wait_for_data({reader}, Seconds(0.1))) continue;
    Client::take(reader, [&](const void* p) {
      const auto& m = *static_cast<const swivel_msg_RunSample*>(p);
      if (outcome != Recording::Outcome::kContinue || m.robot_id == nullptr ||
          robot != m.robot_id) {
        return;
      }
      last_sample = SteadyClock::now();
      outcome = recording.add(m);
    });
    if (recording.started() && SteadyClock::now() >= next_progress) {
      recording.flush();
      std::cout << recording.progress() << std::endl;
      next_progress += std::chrono::seconds(1);
    }
  }
  recording.flush();
  if (!recording.started()) {
    (void)std::remove(options.out.c_str());  // the empty file made to check the path
    if (interrupted()) return 130;
    std::cerr << "swivelctl: robot '" << robot << "' publishes state but sent no "
              << dds::kRunSamplesTopic << " sample within " << seconds_text(timeout)
              << " (is dds.run_samples_rate_hz 0 or off in its configuration?)\n";
    return 1;
  }
  std::cout << recording.summary() << std::endl;
  if (stalled) {
    std::cerr << "swivelctl: no run sample from '" << robot << "' for " << seconds_text(timeout)
              << " (did the daemon stop?); the recording so far is in " << options.out << '\n';
    return 1;
  }
  return outcome == Recording::Outcome::kFailed ? 1 : 0;
}

}  // namespace

void add_record_command(CLI::App& app) {
  auto options = std::make_shared<RecordOptions>();
  CLI::App* sub = app.add_subcommand(
      "record", "write a running daemon's run samples to a run log (the CSV swivel-lab reads)");
  sub->add_option("--out", options->out, "run log to write (CSV)")->required();
  sub->add_option("--duration", options->duration_s,
                  "seconds of robot time to record (default: until Ctrl-C)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--robot", options->robot, "robot id (default: the only one)");
  sub->add_option("--timeout", options->timeout_s,
                  "seconds to wait for the robot and, once recording, for its next sample")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--domain", options->domain_id, "DDS domain id")->capture_default_str();
  sub->callback([options] {
    install_signal_handlers();
    int code = 1;
    try {
      code = run_record(*options);
    } catch (const std::exception& e) {
      std::cerr << "swivelctl: " << e.what() << '\n';
    }
    throw CLI::RuntimeError(code);
  });
}

}  // namespace swivel::ctl
