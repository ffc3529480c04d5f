// SPDX-License-Identifier: Apache-2.0
// The bridge's publisher thread: its schedule, which follows the loop's phase so that a state
// leaves soon after the loop wrote it, the RobotState and ModuleStates it writes, and the
// publish rate it measures. It hands the ROS 2 state to bridge_ros2_state.cpp and writes
// the diagnostics of bridge_diagnostics.cpp at their own rate.
#include <spdlog/spdlog.h>
#include <sys/prctl.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cstdint>
#include <exception>
#include <mutex>
#include <string>
#include <thread>

#include "bridge_entities.hpp"
#include "swivel.h"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/publish_rate_meter.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/rt/clock_offset.hpp"

namespace swivel::dds {

namespace {

swivel_msg_LoopMode to_msg(LoopMode mode) {
  switch (mode) {
    case LoopMode::kIdle: return swivel_msg_LOOP_MODE_IDLE;
    case LoopMode::kVelocity: return swivel_msg_LOOP_MODE_VELOCITY;
    case LoopMode::kCalibration: return swivel_msg_LOOP_MODE_CALIBRATION;
    case LoopMode::kSafeStop: return swivel_msg_LOOP_MODE_SAFE_STOP;
  }
  return swivel_msg_LOOP_MODE_SAFE_STOP;
}

using PublishClock = std::chrono::steady_clock;  // CLOCK_MONOTONIC on Linux, like stamp_s

PublishClock::time_point at_monotonic(double stamp_s) {
  return PublishClock::time_point(
      std::chrono::duration_cast<PublishClock::duration>(std::chrono::duration<double>(stamp_s)));
}

// The publisher follows the loop's phase. It sleeps until kEarly before the cycle it is to
// publish begins, then polls the snapshot (yielding between looks, for at most kSpin) and
// sends that cycle's state as soon as the loop has written it: a sample leaves the
// loop's cycle work plus one DDS hop after its stamp, not up to a publish period later.
// Polling costs the publisher about kEarly plus one cycle's work per sample; the loop
// does nothing for it. A cycle that does not come within kSpin (a stalled loop, or one
// slower than the publish rate) is waited for in steps of kRetry; after kMaxWait the newest
// snapshot goes out and the schedule restarts from it.
constexpr auto kEarly = std::chrono::microseconds(150);
constexpr auto kSpin = std::chrono::microseconds(1000);
constexpr auto kRetry = std::chrono::microseconds(100);
constexpr auto kMaxWait = std::chrono::milliseconds(5);

}  // namespace

void DdsBridge::publish_loop(const std::stop_token& stop) {
  // The default 50 us timer slack would be most of the age this schedule saves.
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  const double period_s = 1.0 / options_.publish_rate_hz;
  const auto period =
      std::chrono::duration_cast<PublishClock::duration>(std::chrono::duration<double>(period_s));
  const auto diagnostics_period = std::chrono::duration_cast<PublishClock::duration>(
      std::chrono::duration<double>(1.0 / options_.diagnostics_rate_hz));
  auto next_diagnostics = PublishClock::now();
  std::uint64_t last_cycle = 0;
  bool have_last = false;
  double due_stamp_s = 0.0;           // the next cycle to publish is the first stamped from here
  PublishClock::time_point due_at{};  // when it is due (epoch: any new cycle is)
  StateSnapshot snapshot;
  std::uint64_t newest_cycle = 0;  // the loop's, published or not
  PublishRateMeter rate(options_.publish_rate_hz);

  // A new cycle (true) and whether it is the one due; the loop's wake-up jitter in the
  // stamps is tolerated up to 1 % of the publish period.
  const auto look = [&](bool& due) {
    const bool have = callbacks_.read_state(snapshot);
    if (have) newest_cycle = snapshot.cycle;
    const bool fresh = have && (!have_last || snapshot.cycle != last_cycle);
    due = fresh && snapshot.stamp_s >= due_stamp_s - 0.01 * period_s;
    return fresh;
  };

  std::unique_lock lock(dds_->wake_mutex);
  while (!stop.stop_requested()) {
    auto next = PublishClock::now() + kRetry;
    try {
      bool due = false;
      bool fresh = look(due);
      const auto spin_until = std::min(PublishClock::now(), due_at) + kSpin;
      while (!due && have_last && PublishClock::now() < spin_until && !stop.stop_requested()) {
        std::this_thread::yield();
        fresh = look(due);
      }
      const auto now = PublishClock::now();
      if (due || (fresh && now >= due_at + kMaxWait)) {
        // Publish only new cycles: a stalled loop shows as a gap, not as repeated samples.
        publish_state(snapshot);
        last_cycle = snapshot.cycle;
        have_last = true;
        due_stamp_s = snapshot.stamp_s + period_s;
        due_at = at_monotonic(due_stamp_s);
        next = due_at - kEarly;
        // After a long stall the snapshot is old: restart the schedule from now.
        if (due_at < now) {
          due_at = now + period;
          due_stamp_s = 0.0;
          next = due_at;
        }
      } else if (now >= due_at + kMaxWait) {
        // Nothing new for a while (a stalled or stopped loop): look once a period.
        next = now + period;
      }
      measure_publish_rate(rate, newest_cycle);
      if (callbacks_.read_diagnostics && PublishClock::now() >= next_diagnostics) {
        publish_diagnostics(callbacks_.read_diagnostics());
        next_diagnostics += diagnostics_period;
        if (next_diagnostics < PublishClock::now()) {
          next_diagnostics = PublishClock::now() + diagnostics_period;
        }
      }
    } catch (const std::exception& e) {
      // Every failure is counted (diagnostics publish_failures); the log has the 1st, 2nd,
      // 4th, 8th, ...: a lasting failure stays visible without flooding it.
      const std::uint64_t failures = publish_failures_.fetch_add(1, std::memory_order_relaxed) + 1;
      if (std::has_single_bit(failures)) {
        spdlog::warn("dds: publishing failed (failure {}): {}", failures, e.what());
      }
    }
    if (callbacks_.read_diagnostics && next_diagnostics < next) next = next_diagnostics;
    dds_->wake.wait_until(lock, stop, next, [] { return false; });
  }
}

void DdsBridge::measure_publish_rate(PublishRateMeter& rate, std::uint64_t newest_cycle) {
  const auto change = rate.update(monotonic_s(), states_published_.load(), newest_cycle);
  achieved_publish_rate_hz_.store(rate.achieved_hz());
  attainable_publish_rate_hz_.store(rate.attainable_hz());
  publish_rate_short_.store(rate.short_of_rate());
  if (change == PublishRateMeter::Change::kFellShort) {
    spdlog::warn(
        "dds: published {:.1f} states/s, below dds.publish_rate_hz {:g}{}: subscribers get "
        "fewer samples than configured (diagnostics: achieved_publish_rate_hz)",
        rate.achieved_hz(), options_.publish_rate_hz,
        rate.attainable_hz() < options_.publish_rate_hz
            ? fmt::format(" and the loop's {:.1f} cycles/s", rate.attainable_hz())
            : std::string());
  } else if (change == PublishRateMeter::Change::kRecovered) {
    spdlog::info("dds: publishing at {:.1f} states/s again (dds.publish_rate_hz {:g})",
                 rate.achieved_hz(), options_.publish_rate_hz);
  }
}

void DdsBridge::publish_state(const StateSnapshot& s) {
  std::array<char, sizeof(ShortName) + 1> plugin{};
  std::copy(s.localization_plugin.begin(), s.localization_plugin.end(), plugin.begin());

  swivel_msg_RobotState state{};
  state.robot_id = c_str(robot_id_);
  state.cycle = s.cycle;
  state.stamp_s = s.stamp_s;
  const rt::RosTime ros_stamp = rt::to_ros_time(s.ros_stamp_ns);
  state.ros_stamp_sec = ros_stamp.sec;
  state.ros_stamp_nanosec = ros_stamp.nanosec;
  state.x_m = s.estimate.pose.x_m;
  state.y_m = s.estimate.pose.y_m;
  state.yaw_rad = s.estimate.pose.yaw_rad;
  state.has_covariance = s.estimate.has_covariance;
  std::copy(s.estimate.covariance.begin(), s.estimate.covariance.end(), state.pose_covariance);
  state.vx_mps = s.odometry_twist.vx_mps;
  state.vy_mps = s.odometry_twist.vy_mps;
  state.wz_radps = s.odometry_twist.wz_radps;
  state.has_twist_covariance = s.has_twist_covariance;
  std::copy(s.twist_covariance.begin(), s.twist_covariance.end(), state.twist_covariance);
  state.cmd_vx_mps = s.command_twist.vx_mps;
  state.cmd_vy_mps = s.command_twist.vy_mps;
  state.cmd_wz_radps = s.command_twist.wz_radps;
  state.gyro_wz_radps = s.gyro_wz_radps;
  state.odometry_residual = s.odometry_residual;
  state.localization_plugin = plugin.data();
  state.localization_swaps = s.localization_swaps;
  state.mode = to_msg(s.mode);
  state.fault_code = static_cast<std::uint16_t>(s.fault);
  state.fault_text = c_str(fault_code_name(s.fault));
  FaultDetail detail = s.fault_detail;
  detail.back() = '\0';
  state.fault_detail = detail.data();
  state.fault_count = s.fault_count;
  state.has_truth = s.has_truth;
  state.truth_x_m = s.truth.x_m;
  state.truth_y_m = s.truth.y_m;
  state.truth_yaw_rad = s.truth.yaw_rad;
  check(dds_write(dds_->state_writer, &state), "dds_write(robot state)");
  states_published_.fetch_add(1, std::memory_order_relaxed);

  std::array<swivel_msg_ModuleState, kMaxModules> module_buffer{};
  const std::uint32_t count = std::min(s.module_count, kMaxModules);
  for (std::uint32_t i = 0; i < count; ++i) {
    module_buffer[i] = {s.modules[i].steer_angle_rad, s.modules[i].steer_rate_cmd_radps,
                        s.modules[i].wheel_rate_cmd_radps, s.modules[i].wheel_rate_meas_radps};
  }
  swivel_msg_ModuleStates modules{};
  modules.robot_id = c_str(robot_id_);
  modules.cycle = s.cycle;
  modules.stamp_s = s.stamp_s;
  modules.modules._maximum = kMaxModules;
  modules.modules._length = count;
  modules.modules._buffer = module_buffer.data();
  modules.modules._release = false;
  check(dds_write(dds_->modules_writer, &modules), "dds_write(module states)");

  if (options_.ros2.enabled) publish_ros2_state(s);
}

}  // namespace swivel::dds
