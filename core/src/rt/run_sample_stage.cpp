// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/run_sample_stage.hpp"

namespace swivel::rt {

void RunSampleStage::publish(const StateSnapshot& state, double now_s) noexcept {
  if (!(sample_period_s_ > 0.0)) return;
  // Half a loop period early counts as on time.
  if (sequence_ != 0 && now_s < next_s_ - 0.5 * loop_period_s_) return;
  push(state);
  next_s_ = (sequence_ == 1 ? now_s : next_s_) + sample_period_s_;
  if (next_s_ <= now_s) next_s_ = now_s + sample_period_s_;
}

void RunSampleStage::push(const StateSnapshot& state) noexcept {
  RunSample r;
  r.sequence = ++sequence_;
  r.cycle = state.cycle;
  r.stamp_s = state.stamp_s;
  r.command_twist = command_;
  r.module_count = state.module_count;
  r.wheel_angle_rad = state.wheel_angle_rad;
  r.steer_angle_rad = state.steer_angle_rad;
  r.gyro_wz_radps = state.gyro_wz_radps;
  if (state.has_truth) {
    r.has_truth = true;
    r.truth = state.truth;
    r.truth_stamp_s = state.stamp_s;
  } else if (mocap_.valid) {
    r.has_truth = true;
    r.truth = mocap_.pose;
    r.truth_stamp_s = mocap_.stamp_s;
  }
  mocap_.valid = false;
  r.estimate = state.estimate.pose;
  r.fault = state.fault;
  r.mode = state.mode;
  if (!ring_.try_push(r)) dropped_.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace swivel::rt
