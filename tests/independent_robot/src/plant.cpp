// SPDX-License-Identifier: Apache-2.0
#include "plant.hpp"

#include <cmath>
#include <span>

#include "swivel/independent/nominal_robots.hpp"

namespace swivel::independent {
namespace {

// a + h * d, field by field.
PlantState add_scaled(const PlantState& a, double h, const PlantState& d) {
  PlantState out;
  out.pose = Pose{a.pose.x_m + h * d.pose.x_m, a.pose.y_m + h * d.pose.y_m,
                  a.pose.yaw_rad + h * d.pose.yaw_rad};
  for (std::size_t i = 0; i < kMaxWheels; ++i) {
    out.wheel_rad[i] = a.wheel_rad[i] + h * d.wheel_rad[i];
    out.steer_rad[i] = a.steer_rad[i] + h * d.steer_rad[i];
    out.wheel_rate_radps[i] = a.wheel_rate_radps[i] + h * d.wheel_rate_radps[i];
    out.steer_rate_radps[i] = a.steer_rate_radps[i] + h * d.steer_rate_radps[i];
  }
  return out;
}

}  // namespace

PlantParams true_plant(const RunSpec& spec, double eccentric_phase_rad) {
  const TrueEffects& t = spec.truth;
  PlantParams p;
  p.robot = spec.robot;
  p.steering = spec.steering;
  p.wheels = wheel_count(spec.robot);
  const DifferentialGeometry d = docent_nominal();
  p.differential = DifferentialGeometry{d.wheel_radius_left_m * t.wheel_radius_scale[0],
                                        d.wheel_radius_right_m * t.wheel_radius_scale[1],
                                        d.track_width_m * t.track_width_scale};
  const std::array<SwpcModule, 4> nominal = swpc4_nominal();
  for (std::size_t i = 0; i < 4; ++i) {
    SwpcModule m = nominal[i];
    m.caster_offset_m *= t.caster_offset_scale[i];
    m.wheel_radius_m *= t.wheel_radius_scale[i];
    m.steering_offset_rad += t.steering_offset_rad[i];
    p.modules[i] = m;
  }
  p.wheel_time_constant_s = t.actuator_time_constant_s;
  // A steering lag of its own replaces the common actuator lag for the steering drives.
  p.steer_time_constant_s =
      t.steering_time_constant_s > 0.0 ? t.steering_time_constant_s : t.actuator_time_constant_s;
  p.slip_gain_per_radps2 = t.slip_gain_per_radps2;
  const OutsideEffects& o = spec.outside;
  if (o.eccentric_wheel > 0) {
    const auto i = static_cast<std::size_t>(o.eccentric_wheel - 1);
    p.eccentric_amplitude[i] = o.eccentric_amplitude;
    p.eccentric_phase_rad[i] = eccentric_phase_rad;
  }
  return p;
}

PlantState Plant::rate(const PlantState& s, const DriveInputs& in, Twist& twist) const {
  PlantState d;
  std::array<double, kMaxWheels> rolling{};
  for (std::size_t i = 0; i < p_.wheels; ++i) {
    double psi_dot = in.wheel_rate_sp[i];
    double psi_ddot = in.wheel_accel[i];
    if (p_.wheel_time_constant_s > 0.0) {
      psi_dot = s.wheel_rate_radps[i];
      psi_ddot = (in.wheel_rate_sp[i] - psi_dot) / p_.wheel_time_constant_s;
      d.wheel_rate_radps[i] = psi_ddot;
    }
    d.wheel_rad[i] = psi_dot;
    const double radius =
        p_.robot == Robot::kDocent
            ? (i == 0 ? p_.differential.wheel_radius_left_m : p_.differential.wheel_radius_right_m)
            : p_.modules[i].wheel_radius_m;
    const double shape =
        1.0 + p_.eccentric_amplitude[i] * std::cos(s.wheel_rad[i] + p_.eccentric_phase_rad[i]);
    // Slip while speeding up in the direction of travel: the contact rolls less than the
    // wheel turns (more while slowing down); and the slow random-walk slip on top.
    const double contact_rate = psi_dot - p_.slip_gain_per_radps2 * std::abs(psi_dot) * psi_ddot;
    rolling[i] = radius * shape * contact_rate * (1.0 - in.slip[i]);
  }

  if (p_.robot == Robot::kDocent) {
    twist = differential_forward(rolling[0], rolling[1], p_.differential.track_width_m);
  } else {
    const std::span<const SwpcModule> modules(p_.modules.data(), p_.wheels);
    const std::span<const double> phi(s.steer_rad.data(), p_.wheels);
    const std::span<const double> speed(rolling.data(), p_.wheels);
    if (p_.steering == Steering::kSelfAligning) {
      // Where the rolling equations leave the motion free (parallel casters, or heading lines
      // through one point), the wheels' own push decides it: the body follows the command.
      twist = swpc_forward_rolling(modules, phi, speed, in.commanded, p_.passive_prior_weight);
      for (std::size_t i = 0; i < p_.wheels; ++i) {
        d.steer_rad[i] = swpc_passive_steer_rate(p_.modules[i], s.steer_rad[i], twist);
      }
    } else {
      for (std::size_t i = 0; i < p_.wheels; ++i) {
        double phi_dot = in.steer_rate_sp[i];
        if (p_.steer_time_constant_s > 0.0) {
          phi_dot = s.steer_rate_radps[i];
          d.steer_rate_radps[i] = (in.steer_rate_sp[i] - phi_dot) / p_.steer_time_constant_s;
        }
        d.steer_rad[i] = phi_dot;
      }
      twist =
          swpc_forward(modules, phi, speed, std::span<const double>(d.steer_rad.data(), p_.wheels));
    }
  }
  const double c = std::cos(s.pose.yaw_rad);
  const double sn = std::sin(s.pose.yaw_rad);
  d.pose = Pose{c * twist.vx_mps - sn * twist.vy_mps, sn * twist.vx_mps + c * twist.vy_mps,
                twist.wz_radps};
  return d;
}

void Plant::advance(PlantState& s, const DriveInputs& in, double h) const {
  Twist unused;
  const PlantState k1 = rate(s, in, unused);
  const PlantState k2 = rate(add_scaled(s, 0.5 * h, k1), in, unused);
  const PlantState k3 = rate(add_scaled(s, 0.5 * h, k2), in, unused);
  const PlantState k4 = rate(add_scaled(s, h, k3), in, unused);
  PlantState sum = add_scaled(k1, 2.0, k2);
  sum = add_scaled(sum, 2.0, k3);
  sum = add_scaled(sum, 1.0, k4);
  s = add_scaled(s, h / 6.0, sum);
}

}  // namespace swivel::independent
