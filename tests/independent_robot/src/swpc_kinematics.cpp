// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/swpc_kinematics.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <cstddef>

namespace swivel::independent {
namespace {

// The rolling-only solve works on (vx, vy, w L) so that its pull towards the prior treats
// translation and rotation alike; L is about the distance of the axes from the centre.
constexpr double kRotationLengthM = 0.25;

struct AxisVelocity {
  double x = 0.0;
  double y = 0.0;
};

AxisVelocity axis_velocity(const SwpcModule& m, const Twist& body) {
  return AxisVelocity{body.vx_mps - body.wz_radps * m.y_m, body.vy_mps + body.wz_radps * m.x_m};
}

}  // namespace

ModuleRates swpc_inverse(const SwpcModule& m, double phi_rad, const Twist& body) {
  const AxisVelocity v = axis_velocity(m, body);
  const double c = std::cos(phi_rad);
  const double s = std::sin(phi_rad);
  return ModuleRates{(c * v.x + s * v.y) / m.wheel_radius_m,
                     (-s * v.x + c * v.y) / m.caster_offset_m - body.wz_radps};
}

double swpc_passive_steer_rate(const SwpcModule& m, double phi_rad, const Twist& body) {
  const AxisVelocity v = axis_velocity(m, body);
  return (-std::sin(phi_rad) * v.x + std::cos(phi_rad) * v.y) / m.caster_offset_m - body.wz_radps;
}

Twist swpc_forward(std::span<const SwpcModule> modules, std::span<const double> phi_rad,
                   std::span<const double> rolling_speed_mps,
                   std::span<const double> steer_rate_radps) {
  // Rows, unknowns (vx, vy, w):
  //   rolling:   c vx + s vy + (x s - y c) w         = r psi_dot
  //   lateral:  -s vx + c vy + (x c + y s - d) w     = d phi_dot
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < modules.size(); ++i) {
    const SwpcModule& m = modules[i];
    const double c = std::cos(phi_rad[i]);
    const double s = std::sin(phi_rad[i]);
    const Eigen::Vector3d rolling(c, s, m.x_m * s - m.y_m * c);
    const Eigen::Vector3d lateral(-s, c, m.x_m * c + m.y_m * s - m.caster_offset_m);
    normal += rolling * rolling.transpose() + lateral * lateral.transpose();
    rhs += rolling * rolling_speed_mps[i] + lateral * (m.caster_offset_m * steer_rate_radps[i]);
  }
  const Eigen::Vector3d z = normal.ldlt().solve(rhs);
  return Twist{z(0), z(1), z(2)};
}

Twist swpc_forward_rolling(std::span<const SwpcModule> modules, std::span<const double> phi_rad,
                           std::span<const double> rolling_speed_mps, const Twist& prior,
                           double weight) {
  Eigen::Matrix3d normal = weight * Eigen::Matrix3d::Identity();
  Eigen::Vector3d rhs =
      weight * Eigen::Vector3d(prior.vx_mps, prior.vy_mps, prior.wz_radps * kRotationLengthM);
  for (std::size_t i = 0; i < modules.size(); ++i) {
    const SwpcModule& m = modules[i];
    const double c = std::cos(phi_rad[i]);
    const double s = std::sin(phi_rad[i]);
    const Eigen::Vector3d rolling(c, s, (m.x_m * s - m.y_m * c) / kRotationLengthM);
    normal += rolling * rolling.transpose();
    rhs += rolling * rolling_speed_mps[i];
  }
  const Eigen::Vector3d z = normal.ldlt().solve(rhs);
  return Twist{z(0), z(1), z(2) / kRotationLengthM};
}

}  // namespace swivel::independent
