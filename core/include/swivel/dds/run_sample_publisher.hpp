// SPDX-License-Identifier: Apache-2.0
#pragma once
// Publishes the loop's run samples (swivel/rt/run_sample.hpp) on swivel_run_samples: every
// sample, in order, for `swivelctl record`. A thread of its own takes them from the loop's
// ring (through a callback, so that this knows nothing of the loop) a few times per sample
// period and writes each with the recording QoS (run_samples_qos(): reliable, keep last
// kRunSamplesHistoryDepth). A jump in the samples' sequence numbers (the loop's ring was full)
// is counted and logged; the recorder sees the same jump.
//
// Nothing here is real-time safe; the loop only pushes into its ring.

#include <dds/dds.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <stop_token>
#include <string>
#include <thread>

#include "swivel/robot_model.hpp"
#include "swivel/rt/run_sample.hpp"

namespace swivel::dds {

/// What the publisher did, for logs and tests.
struct RunSampleCounters {
  std::uint64_t published = 0;       ///< samples written
  std::uint64_t lost_at_source = 0;  ///< samples the loop could not hand over (sequence jumps)
  std::uint64_t write_failures = 0;  ///< samples DDS refused (dds_write failed)
};

class RunSamplePublisher {
 public:
  /// Takes the oldest sample not taken yet into the argument; false when there is none.
  /// Called on the publisher's thread only (the ring's single consumer).
  using TakeSample = std::function<bool(RunSample&)>;

  /// Creates the topic and its writer on `participant` (the daemon's, DdsBridge::participant()).
  /// `period_s` is the time between two samples (ControlLoop::run_sample_period_s()).
  /// @throws DdsError when DDS refuses; std::invalid_argument for an empty robot id, a
  ///         missing callback or a period that is not finite and positive.
  RunSamplePublisher(dds_entity_t participant, std::string robot_id, DrivetrainKind drivetrain,
                     double period_s, TakeSample take);
  /// Stops the thread (see stop()).
  ~RunSamplePublisher();
  RunSamplePublisher(const RunSamplePublisher&) = delete;
  RunSamplePublisher& operator=(const RunSamplePublisher&) = delete;
  RunSamplePublisher(RunSamplePublisher&&) = delete;  // its thread holds `this`
  RunSamplePublisher& operator=(RunSamplePublisher&&) = delete;

  /// Starts the thread. Call once.
  void start();
  /// Publishes what is left in the ring (call it after the loop's last cycle, so that a
  /// recording gets the end of the run), stops the thread and waits up to 1 s for the
  /// readers to acknowledge every sample. Idempotent.
  void stop() noexcept;

  [[nodiscard]] RunSampleCounters counters() const;

 private:
  void run(const std::stop_token& stop);
  void drain();
  void publish(const RunSample& r);

  std::string robot_id_;
  DrivetrainKind drivetrain_;
  double period_s_;
  TakeSample take_;
  dds_entity_t writer_ = 0;
  std::jthread thread_;
  std::uint64_t last_sequence_ = 0;   // publisher thread only
  double next_loss_warning_s_ = 0.0;  // publisher thread only
  bool warned_write_ = false;         // publisher thread only
  std::atomic<std::uint64_t> published_{0};
  std::atomic<std::uint64_t> lost_at_source_{0};
  std::atomic<std::uint64_t> write_failures_{0};
};

}  // namespace swivel::dds
