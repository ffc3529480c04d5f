// SPDX-License-Identifier: Apache-2.0
#pragma once
// The body twist the loop publishes, estimated over a short window of readings instead of
// one cycle's encoder difference (which, at a few counts per cycle, is mostly quantization).
//
// Every encoder channel (wheel angles, unwrapped steering angles) gets a least-squares line
// over the last N readings: its slope is the channel's rate at the window's centre time
// t_c, its value there the fitted angle. Two readings built from those lines, at
// t_c - h and t_c + h (h half the window's span), go through the drivetrain's own forward
// kinematics, so that one estimator serves every drivetrain: the twist is the drivetrain's
// at the fitted angles and rates, and refers to t_c, (N - 1)/2 periods before the newest
// reading (the delay a consumer sees at a steady period).
//
// Covariance from the quantization model: every reading's angle carries an independent
// error, uniform over one count (variance q^2/12, q = 2 pi / counts per revolution), so each
// fitted rate has variance q^2 / (12 sum (t_i - t_c)^2). The drivetrain's twist is linear in
// the rates at fixed angles; its Jacobian is taken by running the forward kinematics once
// more per channel with that channel's rate raised by one standard deviation, and the
// covariance is the sum of the outer products of those columns. It covers what the encoders
// can resolve, not wheel slip (the localization's noise model covers that for the pose).
//
// Fixed capacity (kMaxTwistWindowReadings), no allocation. push() and estimate() are
// real-time safe; estimate() is not noexcept only because a faulty drivetrain may throw, which
// the loop's plugin guard catches.

#include <array>
#include <cstddef>
#include <cstdint>

#include "swivel/plugin/drivetrain.hpp"
#include "swivel/types.hpp"

namespace swivel::rt {

/// Most readings a twist window holds.
inline constexpr std::size_t kMaxTwistWindowReadings = 256;

struct TwistWindowOptions {
  /// N: readings in the window, in [2, kMaxTwistWindowReadings]. 2 is the one-cycle difference.
  std::size_t readings = 21;
  /// One wheel encoder count, rad (2 pi / counts per revolution); 0 when unknown.
  double wheel_resolution_rad = 0.0;
  /// One steering encoder count, rad; 0 when unknown or when the robot does not steer.
  double steer_resolution_rad = 0.0;
};

/// The windowed twist (robot frame) and its covariance.
struct TwistEstimate {
  Twist2 twist;
  /// Row-major over (vx, vy, wz): m^2/s^2, m rad/s^2, rad^2/s^2. Zero without a resolution.
  std::array<double, 9> covariance{};
  bool has_covariance = false;
  double delay_s = 0.0;        ///< newest reading's stamp minus the window's centre time
  std::uint32_t readings = 0;  ///< readings the fit used
  /// The fitted rate of every module's wheel and (unwrapped) steering angle, rad/s, at the
  /// window's centre; modules beyond the readings' count are zero.
  std::array<double, kMaxModules> wheel_rate_radps{};
  std::array<double, kMaxModules> steer_rate_radps{};
};

class TwistWindow {
 public:
  /// Not real-time safe. @throws std::invalid_argument for a window size out of range or a
  /// resolution that is negative or not finite.
  explicit TwistWindow(const TwistWindowOptions& options);

  /// Real-time safe. Forgets every reading.
  void reset() noexcept;

  /// Real-time safe. New encoder resolutions (a robot-model swap) for the covariance from
  /// the next estimate on; false (nothing changes) for one that is negative or not finite.
  bool set_resolutions(double wheel_resolution_rad, double steer_resolution_rad) noexcept;

  /// Real-time safe. Adds one finite reading. A reading that is not later than the newest,
  /// or has another module count, starts the window afresh.
  void push(const HardwareState& reading) noexcept;

  /// Real-time safe. The twist at the window's centre from the readings held (at least 2),
  /// through `drivetrain`'s forward kinematics. kError, `out` untouched, with fewer than two
  /// readings or when the drivetrain refuses the fitted readings. Calls drivetrain.forward()
  /// up to 1 + 2 * modules times (its module states are then the last call's: call the
  /// loop's own forward() afterwards).
  Status estimate(Drivetrain& drivetrain, TwistEstimate& out);

  [[nodiscard]] std::size_t size() const noexcept { return count_; }
  [[nodiscard]] const TwistWindowOptions& options() const noexcept { return options_; }

 private:
  using Column = std::array<double, kMaxTwistWindowReadings>;

  TwistWindowOptions options_;
  std::size_t capacity_;
  std::array<double, kMaxTwistWindowReadings> stamps_{};
  // Channel i < kMaxModules: wheel i; kMaxModules + i: steering i (unwrapped). Filled slots
  // are [0, count_): the fit does not depend on their order.
  std::array<Column, std::size_t{2} * kMaxModules> channels_{};
  std::size_t count_ = 0;
  std::size_t next_ = 0;
  std::uint32_t module_count_ = 0;
  double newest_s_ = 0.0;
  double oldest_s_ = 0.0;
  std::array<double, kMaxModules> last_steer_raw_rad_{};
  std::array<double, kMaxModules> steer_unwrapped_rad_{};
  // The fitted readings handed to the drivetrain (members: large, kept off the loop's stack).
  HardwareState before_{};
  HardwareState after_{};
  std::array<double, std::size_t{2} * kMaxModules> slopes_{};
  std::array<double, std::size_t{2} * kMaxModules> means_{};
};

}  // namespace swivel::rt
