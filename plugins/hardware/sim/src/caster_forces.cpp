// SPDX-License-Identifier: Apache-2.0
#include "swivel/sim/caster_forces.hpp"

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace swivel::sim {
namespace {

constexpr double kGravity = 9.81;
constexpr int kMaxIterations = 30;
constexpr int kMaxHalvings = 12;
// Converged when the step moves no unknown by more than this (m/s, rad/s).
constexpr double kStepTolerance = 1e-6;
// Or when the balance is this close (friction units; servo errors in units of the yield).
constexpr double kBalanceTolerance = 1e-6;

using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 3 + kMaxModules, 1>;

// The balance's Jacobian, an arrow: the body's rows depend on everything, each caster's row
// on the body's twist and its own rate only.
struct ArrowJacobian {
  Eigen::Matrix3d body;                                   // body rows, twist columns
  std::array<Eigen::Vector3d, kMaxModules> body_rate;     // body rows, a caster's rate column
  std::array<Eigen::Vector3d, kMaxModules> caster_twist;  // a caster's row, twist columns
  std::array<double, kMaxModules> caster_rate{};          // a caster's row, its rate column

  void clear(std::size_t n) {
    body.setZero();
    for (std::size_t i = 0; i < n; ++i) {
      body_rate[i].setZero();
      caster_twist[i].setZero();
      caster_rate[i] = 0.0;
    }
  }

  // Solves J step = r by eliminating the casters' rates (their block is diagonal and never
  // singular: a servo always resists its caster's rate). False if the twist's block is.
  bool solve(std::size_t n, const Vector& r, Vector& step) const {
    Eigen::Matrix3d reduced = body;
    Eigen::Vector3d rhs = r.head<3>();
    for (std::size_t i = 0; i < n; ++i) {
      reduced -= body_rate[i] * caster_twist[i].transpose() / caster_rate[i];
      rhs -= body_rate[i] * r(static_cast<Eigen::Index>(3 + i)) / caster_rate[i];
    }
    const Eigen::PartialPivLU<Eigen::Matrix3d> lu(reduced);
    const Eigen::Vector3d twist = lu.solve(rhs);
    if (!twist.allFinite()) return false;
    step.head<3>() = twist;
    for (std::size_t i = 0; i < n; ++i) {
      const auto row = static_cast<Eigen::Index>(3 + i);
      step(row) = (r(row) - caster_twist[i].dot(twist)) / caster_rate[i];
    }
    return true;
  }
};

// The balance of one step for the unknowns x = (vx, vy, w, steering rates...): the body's
// force and moment (units of one tyre's friction) and each caster's servo against its tyre
// (over the yield), with its Jacobian.
class StepBalance {
 public:
  StepBalance(const CasterForces& model, std::span<const SwpcModuleParams> modules,
              std::span<const CasterState> casters, double h, const Twist2& previous)
      : model_(model), modules_(modules), casters_(casters), h_(h), previous_(previous) {
    const auto n = static_cast<double>(modules.size());
    // The body's mass over one tyre's friction force: m / (mu m g / n).
    mass_ = n / (model.friction_coefficient * kGravity);
    double r2 = 0.0;
    for (const SwpcModuleParams& m : modules) r2 += m.x_m * m.x_m + m.y_m * m.y_m;
    // Yaw inertia as a disc through the modules' ring.
    inertia_ = mass_ * 0.5 * r2 / n;
    for (std::size_t i = 0; i < modules.size(); ++i) {
      cos_[i] = std::cos(casters[i].phi_rad);
      sin_[i] = std::sin(casters[i].phi_rad);
    }
  }

  // r = balance(x); with `jac`, also its Jacobian.
  void operator()(const Vector& x, Vector& r, ArrowJacobian* jac) const noexcept {
    const auto size = x.size();
    if (jac != nullptr) jac->clear(modules_.size());
    r.setZero(size);
    const double k = model_.creep_stiffness;
    for (std::size_t i = 0; i < modules_.size(); ++i) {
      const SwpcModuleParams& m = modules_[i];
      const CasterState& s = casters_[i];
      const auto row = static_cast<Eigen::Index>(3 + i);
      const double c = cos_[i];
      const double sn = sin_[i];
      const double d = m.caster_offset_m;
      const double axis_vx = x(0) - x(2) * m.y_m;
      const double axis_vy = x(1) + x(2) * m.x_m;
      // The contact's velocity along the wheel against the wheel's rolling, and across it;
      // their derivatives by (vx, vy, w, this caster's rate).
      const double along_slip = c * axis_vx + sn * axis_vy - m.wheel_radius_m * s.wheel_rate_radps;
      const double across_slip = -sn * axis_vx + c * axis_vy - d * (x(2) + x(row));
      const std::array<double, 4> d_along{c, sn, -c * m.y_m + sn * m.x_m, 0.0};
      const std::array<double, 4> d_across{-sn, c, sn * m.y_m + c * m.x_m - d, -d};
      const double axis_speed = std::hypot(axis_vx, axis_vy);
      const bool creeping = axis_speed < model_.creep_floor_mps;
      const double speed = creeping ? model_.creep_floor_mps : axis_speed;
      std::array<double, 4> d_speed{};
      if (!creeping) {
        d_speed = {axis_vx / speed, axis_vy / speed, (-axis_vx * m.y_m + axis_vy * m.x_m) / speed,
                   0.0};
      }
      const double p = -k * along_slip / speed;
      const double q = -k * across_slip / speed;
      const double cap = 1.0 / std::sqrt(1.0 + p * p + q * q);
      const double along = p * cap;
      const double across = q * cap;
      const double gx = c * along - sn * across;
      const double gy = sn * along + c * across;
      const double contact_x = m.x_m - d * c;
      const double contact_y = m.y_m - d * sn;
      r(0) += gx;
      r(1) += gy;
      r(2) += contact_x * gy - contact_y * gx;
      const double error = s.servo_ref_rad + h_ * s.servo_rate_radps - (s.phi_rad + h_ * x(row));
      const double servo = error + model_.servo_damping_s * (s.servo_rate_radps - x(row));
      const double yield = model_.steering_yield_rad;
      r(row) = servo / yield - across;
      if (jac == nullptr) continue;
      const double cap3 = cap * cap * cap;
      for (std::size_t v = 0; v < 4; ++v) {
        const double dp = -k * (d_along[v] - along_slip * d_speed[v] / speed) / speed;
        const double dq = -k * (d_across[v] - across_slip * d_speed[v] / speed) / speed;
        const double d_along_force = cap3 * ((1.0 + q * q) * dp - p * q * dq);
        const double d_across_force = cap3 * ((1.0 + p * p) * dq - p * q * dp);
        const double dgx = c * d_along_force - sn * d_across_force;
        const double dgy = sn * d_along_force + c * d_across_force;
        const Eigen::Vector3d body(dgx, dgy, contact_x * dgy - contact_y * dgx);
        if (v < 3) {
          jac->body.col(static_cast<Eigen::Index>(v)) += body;
          jac->caster_twist[i](static_cast<Eigen::Index>(v)) = -d_across_force;
        } else {
          jac->body_rate[i] = body;
          jac->caster_rate[i] = -d_across_force;
        }
      }
      jac->caster_rate[i] -= (h_ + model_.servo_damping_s) / yield;
    }
    r(0) -= mass_ * (x(0) - previous_.vx_mps) / h_;
    r(1) -= mass_ * (x(1) - previous_.vy_mps) / h_;
    r(2) -= inertia_ * (x(2) - previous_.wz_radps) / h_;
    if (jac != nullptr) {
      jac->body(0, 0) -= mass_ / h_;
      jac->body(1, 1) -= mass_ / h_;
      jac->body(2, 2) -= inertia_ / h_;
    }
  }

 private:
  const CasterForces& model_;
  std::span<const SwpcModuleParams> modules_;
  std::span<const CasterState> casters_;
  double h_;
  Twist2 previous_;
  double mass_ = 0.0;
  double inertia_ = 0.0;
  std::array<double, kMaxModules> cos_{};
  std::array<double, kMaxModules> sin_{};
};

}  // namespace

bool caster_force_step(const CasterForces& model, std::span<const SwpcModuleParams> modules,
                       std::span<const CasterState> casters, double h_s,
                       const Twist2& previous_twist, Twist2& twist,
                       std::span<double> steer_rate_radps) noexcept {
  const std::size_t n = modules.size();
  const auto size = static_cast<Eigen::Index>(3 + n);
  const StepBalance balance(model, modules, casters, h_s, previous_twist);
  Vector x(size);
  x.head<3>() << twist.vx_mps, twist.vy_mps, twist.wz_radps;
  for (std::size_t i = 0; i < n; ++i) x(static_cast<Eigen::Index>(3 + i)) = steer_rate_radps[i];
  Vector r(size);
  Vector trial(size);
  Vector r_trial(size);
  Vector step(size);
  ArrowJacobian jac;
  bool converged = false;
  balance(x, r, &jac);
  for (int iteration = 0; iteration < kMaxIterations && !converged; ++iteration) {
    if (r.cwiseAbs().maxCoeff() < kBalanceTolerance) {
      converged = true;
      break;
    }
    if (!jac.solve(n, r, step)) break;
    // Newton's step, halved until the balance improves (the friction caps bend it sharply).
    // The whole step, mostly taken, brings its Jacobian; a halved one gets it once taken.
    double scale = 1.0;
    bool improved = false;
    int halving = 0;
    for (; halving < kMaxHalvings && !improved; ++halving) {
      trial = x - scale * step;
      balance(trial, r_trial, halving == 0 ? &jac : nullptr);
      improved = r_trial.squaredNorm() < r.squaredNorm();
      if (!improved) scale *= 0.5;
    }
    // Within rounding of the balance, no step improves it.
    converged = (scale * step).cwiseAbs().maxCoeff() < kStepTolerance;
    if (!improved) break;
    x = trial;
    r = r_trial;
    if (halving > 1 && !converged) balance(x, r, &jac);
  }
  twist = Twist2{x(0), x(1), x(2)};
  for (std::size_t i = 0; i < n; ++i) steer_rate_radps[i] = x(static_cast<Eigen::Index>(3 + i));
  return converged;
}

void validate_caster_forces(const CasterForces& model) {
  const auto positive = [](double v, const char* name) {
    if (!std::isfinite(v) || !(v > 0.0)) {
      throw std::invalid_argument(std::string("caster forces: ") + name +
                                  " must be finite and positive");
    }
  };
  if (!std::isfinite(model.steering_yield_rad) || model.steering_yield_rad < 0.0) {
    throw std::invalid_argument("caster forces: steering_yield_rad must be finite and >= 0");
  }
  positive(model.servo_damping_s, "servo_damping_s");
  positive(model.creep_stiffness, "creep_stiffness");
  positive(model.creep_floor_mps, "creep_floor_mps");
  positive(model.friction_coefficient, "friction_coefficient");
}

}  // namespace swivel::sim
