// SPDX-License-Identifier: Apache-2.0
#include "controlled_stop.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "swivel/clock.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {

void bring_to_rest(rt::ControlLoop& loop, const MotionLimits& limits,
                   const ControlledStopConfig& stop) noexcept {
  if (!loop.running()) return;
  loop.request_controlled_stop(monotonic_s());  // no-op when the signal asked already
  try {
    const StateSnapshot from = loop.latest();
    const double a_linear = limits.linear_acceleration_mps2.value_or(stop.linear_deceleration_mps2);
    const double a_angular =
        limits.angular_acceleration_radps2.value_or(stop.angular_deceleration_radps2);
    const Twist2& v = from.command_twist;
    double ramp_s = std::max({std::abs(v.vx_mps) / a_linear, std::abs(v.vy_mps) / a_linear,
                              std::abs(v.wz_radps) / a_angular});
    if (limits.linear_jerk_mps3) ramp_s += a_linear / *limits.linear_jerk_mps3;
    if (limits.angular_jerk_radps3) ramp_s += a_angular / *limits.angular_jerk_radps3;
    const double limit_s = ramp_s + 1.0;  // and the drives' own lag
    spdlog::info(
        "stopping: bringing the robot to rest from vx={:.3f} m/s vy={:.3f} m/s "
        "wz={:.3f} rad/s (controlled stop at {} m/s^2, {} rad/s^2)",
        v.vx_mps, v.vy_mps, v.wz_radps, a_linear, a_angular);
    const double start_s = monotonic_s();
    for (;;) {
      const StateSnapshot s = loop.latest();
      const Twist2& c = s.command_twist;
      const Twist2& m = s.odometry_twist;
      const bool commanded_zero = c.vx_mps == 0.0 && c.vy_mps == 0.0 && c.wz_radps == 0.0;
      const bool measured_still =
          std::hypot(m.vx_mps, m.vy_mps) < 0.005 && std::abs(m.wz_radps) < 0.01;
      if (s.stopping && commanded_zero && measured_still) {
        if (s.has_truth && from.has_truth) {
          spdlog::info(
              "robot at rest after {:.3f} s; it travelled {:.4f} m meanwhile "
              "(simulator's ground truth)",
              s.stamp_s - from.stamp_s,
              std::hypot(s.truth.x_m - from.truth.x_m, s.truth.y_m - from.truth.y_m));
        } else {
          spdlog::info("robot at rest after {:.3f} s", s.stamp_s - from.stamp_s);
        }
        return;
      }
      if (monotonic_s() - start_s > limit_s || !loop.running()) {
        spdlog::error(
            "the robot did not come to rest within {:.2f} s; stopping the loop anyway "
            "(zero setpoints at once)",
            limit_s);
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  } catch (const std::exception& e) {
    try {
      spdlog::error("controlled stop: {}", e.what());
    } catch (...) {
    }
  }
}

}  // namespace swivel::daemon
