// SPDX-License-Identifier: Apache-2.0
#pragma once
// In-process stand-ins for the hardware, drivetrain and localization plugins: a two-wheel
// differential robot whose "hardware" integrates the commanded wheel rates exactly. Knobs
// (atomics, so a test thread may turn them while a loop thread runs) inject the failures the
// loop must handle. Not real plugins: no YAML, no shared library.

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <span>
#include <stdexcept>
#include <vector>

#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"

namespace swivel::test {

inline constexpr double kFakeWheelRadiusM = 0.1;
inline constexpr double kFakeTrackWidthM = 0.5;

/// Integrates the last written wheel rates into cumulative wheel angles and a true pose.
class FakeHardware final : public Hardware {
 public:
  std::atomic<bool> inject_nan{false};  ///< next reads carry a NaN wheel angle
  std::atomic<bool> fail_read{false};   ///< read() returns kError

  void configure(const PluginContext&) override {}

  void on_error(const char* /*cause*/) noexcept override {
    on_errors.fetch_add(1, std::memory_order_relaxed);
  }

  Status read(double stamp_s, HardwareState& out) noexcept override {
    reads.fetch_add(1, std::memory_order_relaxed);
    if (fail_read.load(std::memory_order_relaxed)) return Status::kError;
    if (has_stamp_) {
      const double dt = stamp_s - stamp_s_;
      const double dl = rate_[0] * dt;
      const double dr = rate_[1] * dt;
      angle_[0] += dl;
      angle_[1] += dr;
      const double ds = kFakeWheelRadiusM * (dl + dr) / 2.0;
      const double dyaw = kFakeWheelRadiusM * (dr - dl) / kFakeTrackWidthM;
      const double mid = truth_.yaw_rad + dyaw / 2.0;
      truth_.x_m += ds * std::cos(mid);
      truth_.y_m += ds * std::sin(mid);
      truth_.yaw_rad += dyaw;
      gyro_ = dt > 0.0 ? dyaw / dt : 0.0;
    }
    stamp_s_ = stamp_s;
    has_stamp_ = true;
    out = HardwareState{};
    out.stamp_s = stamp_s;
    out.module_count = 2;
    out.wheel_angle_rad[0] = angle_[0];
    out.wheel_angle_rad[1] = angle_[1];
    out.gyro_wz_radps = gyro_;
    out.gyro_valid = true;
    if (inject_nan.load(std::memory_order_relaxed)) out.wheel_angle_rad[1] = std::nan("");
    return Status::kOk;
  }

  Status write(const ActuatorCommand& command) noexcept override {
    rate_[0] = command.wheel_rate_radps[0];
    rate_[1] = command.wheel_rate_radps[1];
    last_left_radps.store(rate_[0], std::memory_order_relaxed);
    last_right_radps.store(rate_[1], std::memory_order_relaxed);
    writes.fetch_add(1, std::memory_order_relaxed);
    return Status::kOk;
  }

  bool ground_truth(Pose2& out) const noexcept override {
    out = truth_;
    return true;
  }

  std::atomic<double> last_left_radps{0.0};  ///< last written setpoints
  std::atomic<double> last_right_radps{0.0};
  std::atomic<std::uint64_t> reads{0};
  std::atomic<std::uint64_t> writes{0};
  std::atomic<std::uint64_t> on_errors{0};  ///< on_error() calls

 private:
  double angle_[2] = {0.0, 0.0};
  double rate_[2] = {0.0, 0.0};
  double stamp_s_ = 0.0;
  bool has_stamp_ = false;
  double gyro_ = 0.0;
  Pose2 truth_;
};

/// Differential kinematics with the fake geometry.
class FakeDrivetrain final : public Drivetrain {
 public:
  std::atomic<bool> fail_forward{false};
  /// inverse() scales the twist down to this forward speed, as wheel limits would.
  std::atomic<double> max_speed_mps{std::numeric_limits<double>::infinity()};

  void configure(const PluginContext&) override {}
  [[nodiscard]] std::uint32_t module_count() const noexcept override { return 2; }

  Status forward(const HardwareState& previous, const HardwareState& current,
                 OdometryIncrement& out) noexcept override {
    if (fail_forward.load(std::memory_order_relaxed)) return Status::kError;
    out = OdometryIncrement{};
    out.dt_s = current.stamp_s - previous.stamp_s;
    const double dl = current.wheel_angle_rad[0] - previous.wheel_angle_rad[0];
    const double dr = current.wheel_angle_rad[1] - previous.wheel_angle_rad[1];
    const double ds = kFakeWheelRadiusM * (dl + dr) / 2.0;
    const double dyaw = kFakeWheelRadiusM * (dr - dl) / kFakeTrackWidthM;
    out.delta = {ds * std::cos(dyaw / 2.0), ds * std::sin(dyaw / 2.0), dyaw};
    if (out.dt_s > 0.0) out.twist = {ds / out.dt_s, 0.0, dyaw / out.dt_s};
    out.valid = out.dt_s > 0.0;
    measured_[0] = out.dt_s > 0.0 ? dl / out.dt_s : 0.0;
    measured_[1] = out.dt_s > 0.0 ? dr / out.dt_s : 0.0;
    return Status::kOk;
  }

  Status inverse(const Twist2& requested, const HardwareState&, double, ActuatorCommand& out,
                 Twist2& applied) noexcept override {
    const double max_speed = max_speed_mps.load(std::memory_order_relaxed);
    const double scale =
        std::abs(requested.vx_mps) > max_speed ? max_speed / std::abs(requested.vx_mps) : 1.0;
    const Twist2 command{requested.vx_mps * scale, 0.0, requested.wz_radps * scale};
    out = ActuatorCommand{};
    out.module_count = 2;
    const double half = command.wz_radps * kFakeTrackWidthM / 2.0;
    out.wheel_rate_radps[0] = (command.vx_mps - half) / kFakeWheelRadiusM;
    out.wheel_rate_radps[1] = (command.vx_mps + half) / kFakeWheelRadiusM;
    commanded_[0] = out.wheel_rate_radps[0];
    commanded_[1] = out.wheel_rate_radps[1];
    applied = {command.vx_mps, 0.0, command.wz_radps};
    return Status::kOk;
  }

  void module_states(std::span<ModuleState> out) const noexcept override {
    for (std::size_t i = 0; i < out.size() && i < 2; ++i) {
      out[i] = ModuleState{};
      out[i].wheel_rate_cmd_radps = commanded_[i];
      out[i].wheel_rate_meas_radps = measured_[i];
    }
  }

 private:
  double commanded_[2] = {0.0, 0.0};
  double measured_[2] = {0.0, 0.0};
};

/// Dead reckoning from the odometry increments.
class FakeLocalization final : public Localization {
 public:
  std::atomic<bool> fail_update{false};         ///< update() returns kError
  std::atomic<bool> allocate_in_update{false};  ///< update() grows a vector (a planted bug)
  std::atomic<bool> malloc_in_update{false};    ///< update() calls malloc/free directly
  std::atomic<bool> throw_in_update{false};     ///< update() throws (a plugin breaking the rules)
  std::atomic<bool> refuse_hand_over{false};    ///< hand_over() returns kError
  std::atomic<bool> nan_covariance{false};      ///< update() leaves a NaN in the covariance

  void configure(const PluginContext&) override {}
  void reset(const PoseEstimate& initial) override { estimate_ = initial; }

  Status hand_over(const PoseEstimate& current) noexcept override {
    if (refuse_hand_over.load(std::memory_order_relaxed)) {
      error_ = "fake hand-over refusal";
      return Status::kError;
    }
    estimate_.pose = current.pose;
    if (current.has_covariance) {
      estimate_.covariance = current.covariance;
      estimate_.has_covariance = true;
    }
    hand_overs.fetch_add(1, std::memory_order_relaxed);
    return Status::kOk;
  }

  // Not noexcept: this fake can break the rule on purpose (throw_in_update).
  Status update(const OdometryIncrement& odometry, const HardwareState& readings) override {
    updates.fetch_add(1, std::memory_order_relaxed);
    if (throw_in_update.load(std::memory_order_relaxed)) {
      throw std::runtime_error("fake localization threw");
    }
    if (readings.motion_capture.valid) {
      last_motion_capture_x_m.store(readings.motion_capture.pose.x_m, std::memory_order_relaxed);
    }
    if (fail_update.load(std::memory_order_relaxed)) {
      error_ = "fake update failure";
      return Status::kError;
    }
    if (allocate_in_update.load(std::memory_order_relaxed)) {
      try {
        history_.push_back(estimate_.pose);  // grows: allocates now and then
        history_.shrink_to_fit();            // and so every time
      } catch (...) {
        return Status::kError;
      }
    }
    if (malloc_in_update.load(std::memory_order_relaxed)) {
      // A raw allocation on the loop, which the allocation guard must see.
      void* volatile block = std::malloc(64);  // NOLINT(cppcoreguidelines-no-malloc)
      std::free(block);                        // NOLINT(cppcoreguidelines-no-malloc)
    }
    if (nan_covariance.load(std::memory_order_relaxed)) {
      estimate_.has_covariance = true;
      estimate_.covariance = {1e-4, 0.0, 0.0, 0.0, 1e-4, 0.0, 0.0, 0.0, 1e-3};
      estimate_.covariance[4] = std::numeric_limits<double>::quiet_NaN();
    }
    if (!odometry.valid) return Status::kOk;
    Pose2& p = estimate_.pose;
    const double c = std::cos(p.yaw_rad);
    const double s = std::sin(p.yaw_rad);
    p.x_m += c * odometry.delta.x_m - s * odometry.delta.y_m;
    p.y_m += s * odometry.delta.x_m + c * odometry.delta.y_m;
    p.yaw_rad += odometry.delta.yaw_rad;
    return Status::kOk;
  }

  [[nodiscard]] PoseEstimate estimate() const noexcept override { return estimate_; }
  [[nodiscard]] const char* last_error() const noexcept override { return error_; }

  std::atomic<std::uint64_t> updates{0};
  std::atomic<std::uint64_t> hand_overs{0};
  std::atomic<double> last_motion_capture_x_m{0.0};  ///< x of the last fix update() saw

 private:
  PoseEstimate estimate_;
  std::vector<Pose2> history_;
  const char* error_ = "";
};

}  // namespace swivel::test
