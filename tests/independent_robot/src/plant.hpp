// SPDX-License-Identifier: Apache-2.0
#pragma once
// The true robot's motion: drives, wheel-ground contact and body kinematics as one ordinary
// differential equation, advanced with classic fourth-order Runge-Kutta while the
// controller's setpoints are held.

#include <array>
#include <cstddef>

#include "swivel/independent/differential_kinematics.hpp"
#include "swivel/independent/run_spec.hpp"
#include "swivel/independent/swpc_kinematics.hpp"

namespace swivel::independent {

struct PlantState {
  Pose pose;                                          ///< on the floor, yaw unwrapped
  std::array<double, kMaxWheels> wheel_rad{};         ///< psi: each wheel's own angle
  std::array<double, kMaxWheels> steer_rad{};         ///< true steering angles (swpc4)
  std::array<double, kMaxWheels> wheel_rate_radps{};  ///< drive output, used with a lag
  std::array<double, kMaxWheels> steer_rate_radps{};  ///< drive output, used with a lag
};

/// What is held over one control period.
struct DriveInputs {
  std::array<double, kMaxWheels> wheel_rate_sp{};
  std::array<double, kMaxWheels> wheel_accel{};  ///< ideal drives: setpoint change / period
  std::array<double, kMaxWheels> steer_rate_sp{};
  std::array<double, kMaxWheels> slip{};  ///< random-walk slip ratio s_i
  Twist commanded;  ///< the controller's twist after its limits (passive casters, see Plant)
};

/// The true robot's parameters, effects folded in.
struct PlantParams {
  Robot robot = Robot::kDocent;
  Steering steering = Steering::kPowered;
  std::size_t wheels = 2;
  DifferentialGeometry differential;
  std::array<SwpcModule, kMaxWheels> modules{};
  double wheel_time_constant_s = 0.0;  ///< 0: the drive follows its setpoint at once
  double steer_time_constant_s = 0.0;
  double slip_gain_per_radps2 = 0.0;
  /// Passive casters: how strongly a direction the rolling equations leave free follows the
  /// commanded twist (swpc_forward_rolling's weight). 1e-3 keeps the slip noise's effect in
  /// such a direction below about 16 x its size (weight^-1/2 / 2).
  double passive_prior_weight = 1e-3;
  std::array<double, kMaxWheels> eccentric_amplitude{};
  std::array<double, kMaxWheels> eccentric_phase_rad{};
};

/// The true robot of `spec`; `eccentric_phase_rad` places the eccentric wheel's bulge.
PlantParams true_plant(const RunSpec& spec, double eccentric_phase_rad);

class Plant {
 public:
  explicit Plant(const PlantParams& params) : p_(params) {}

  /// The state's time derivative, and the body twist at `s`.
  PlantState rate(const PlantState& s, const DriveInputs& in, Twist& twist) const;

  /// Advances `s` by `h` seconds with the inputs held.
  void advance(PlantState& s, const DriveInputs& in, double h) const;

  [[nodiscard]] const PlantParams& params() const { return p_; }

 private:
  PlantParams p_;
};

}  // namespace swivel::independent
