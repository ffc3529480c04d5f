// SPDX-License-Identifier: Apache-2.0
// The physics (README.md "Physics"): a 1 kHz loop of the robot's own controller and a
// rigid body on force-based contacts, integrated by implicit Euler with Newton's method on
// the body twist and the steering rates.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "open_loop.hpp"
#include "planner.hpp"
#include "random.hpp"
#include "swivel/second/second_robot.hpp"

namespace swivel::second {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kStepS = 0.001;
constexpr double kGravity = 9.81;
constexpr double kCreepSpeedFloorMps = 0.05;  // slip is measured against at least this speed
constexpr double kLateralStiffnessShare = 0.8;
// Steering axis: inertia and a PD servo on the integrated rate setpoint, with feedforward.
constexpr double kSteeringInertia = 0.004;  // kg m^2
constexpr double kSteeringKp = 60.0;        // N m / rad
constexpr double kSteeringKd = 0.9;         // N m s / rad
constexpr double kSteeringViscous = 0.002;  // N m s / rad
constexpr double kFrictionSmoothingRadps = 0.02;
constexpr double kMocapLossProbability = 0.005;

double wrap(double a) {
  a = std::fmod(a + kPi, 2 * kPi);
  if (a <= 0) a += 2 * kPi;
  return a - kPi;
}

// The true robot: one contact per wheel.
struct Contact {
  double px = 0;  // steering axis (differential: wheel centre)
  double py = 0;
  double trail = 0;  // caster offset d
  double radius = 0;
  double offset = 0;  // steering offset: encoder reads true - offset
};

struct State {
  double pose[3] = {0, 0, 0};
  double twist[3] = {0, 0, 0};
  std::vector<double> psi, psi_rate, phi, phi_rate, phi_ref, wheel_set, steer_set, ground, travel;
  double limited[3] = {0, 0, 0};
};

class Robot {
 public:
  Robot(const RunSpec& spec, const Design& d) : spec_(spec), d_(d), n_(d.wheel_count()) {
    const Truth& tr = spec.truth;
    const auto scale = [](const std::vector<double>& v, std::size_t i) {
      return i < v.size() ? v[i] : 1.0;
    };
    for (std::size_t i = 0; i < n_; ++i) {
      Contact c;
      if (d.drive == Drive::kDifferential) {
        const double half = d.track_width_m * tr.track_width_scale / 2;
        c.py = i == 0 ? half : -half;
        c.radius = (i == 0 ? d.wheel_radius_left_m : d.wheel_radius_right_m) *
                   scale(tr.wheel_radius_scale, i);
      } else {
        const CasterModule& m = d.modules[i];
        c.px = m.x_m;
        c.py = m.y_m;
        c.trail = m.caster_offset_m * scale(tr.caster_offset_scale, i);
        c.radius = m.wheel_radius_m * scale(tr.wheel_radius_scale, i);
        c.offset = i < tr.steering_offset_rad.size() ? tr.steering_offset_rad[i] : 0.0;
      }
      contacts_.push_back(c);
    }
    swpc_ = d.drive == Drive::kSwpc;
    load_ = d.mass_kg * kGravity / static_cast<double>(n_);
    lin_limit_ =
        tr.linear_accel_limit_mps2 > 0 ? tr.linear_accel_limit_mps2 : d.linear_accel_limit_mps2;
    ang_limit_ = tr.angular_accel_limit_radps2 > 0 ? tr.angular_accel_limit_radps2
                                                   : d.angular_accel_limit_radps2;
    steer_limit_ = tr.steering_rate_limit_radps > 0 ? tr.steering_rate_limit_radps
                                                    : d.steering_rate_limit_radps;
  }

  [[nodiscard]] std::size_t n() const { return n_; }
  [[nodiscard]] const Contact& contact(std::size_t i) const { return contacts_[i]; }

  // The robot's controller: limit the command, inverse kinematics of the nominal model at
  // the measured steering angles, drive setpoints through their lags.
  void control(State& s, const double cmd[3], const std::vector<double>& measured_steer) const {
    const double lim[3] = {lin_limit_ * kStepS, lin_limit_ * kStepS, ang_limit_ * kStepS};
    for (int a = 0; a < 3; ++a) s.limited[a] += std::clamp(cmd[a] - s.limited[a], -lim[a], lim[a]);
    const double vx = s.limited[0];
    const double vy = s.limited[1];
    const double w = s.limited[2];
    std::vector<double> wheel(n_, 0.0);
    std::vector<double> steer(n_, 0.0);
    if (!swpc_) {
      wheel[0] = (vx - w * d_.track_width_m / 2) / d_.wheel_radius_left_m;
      wheel[1] = (vx + w * d_.track_width_m / 2) / d_.wheel_radius_right_m;
    } else {
      for (std::size_t i = 0; i < n_; ++i) {
        const CasterModule& m = d_.modules[i];
        const double sx = vx - w * m.y_m;
        const double sy = vy + w * m.x_m;
        const double c = std::cos(measured_steer[i]);
        const double sn = std::sin(measured_steer[i]);
        wheel[i] = (c * sx + sn * sy) / m.wheel_radius_m;
        steer[i] = (-sn * sx + c * sy) / m.caster_offset_m - w;
        if (steer_limit_ > 0) steer[i] = std::clamp(steer[i], -steer_limit_, steer_limit_);
      }
    }
    const Truth& tr = spec_.truth;
    const double wheel_lag = tr.actuator_lag_s;
    const double steer_lag = tr.steering_lag_s > 0 ? tr.steering_lag_s : tr.actuator_lag_s;
    const double kw = wheel_lag > 0 ? 1.0 - std::exp(-kStepS / wheel_lag) : 1.0;
    const double ks = steer_lag > 0 ? 1.0 - std::exp(-kStepS / steer_lag) : 1.0;
    for (std::size_t i = 0; i < n_; ++i) {
      s.wheel_set[i] += kw * (wheel[i] - s.wheel_set[i]);
      s.steer_set[i] += ks * (steer[i] - s.steer_set[i]);
    }
  }

  // One implicit Euler step of the body and the steering axes.
  void step(State& s) const {
    const std::size_t m = swpc_ ? n_ : 0;
    const std::size_t dim = 3 + m;
    std::vector<double> speed_norm(n_);
    for (std::size_t i = 0; i < n_; ++i) {
      const Contact& c = contacts_[i];
      speed_norm[i] = std::max(
          {std::abs(c.radius * s.wheel_set[i]), std::abs(s.ground[i]), kCreepSpeedFloorMps});
    }
    Eigen::VectorXd q(dim);
    for (std::size_t a = 0; a < 3; ++a) q[static_cast<Eigen::Index>(a)] = s.twist[a];
    for (std::size_t i = 0; i < m; ++i) q[static_cast<Eigen::Index>(3 + i)] = s.phi_rate[i];
    Eigen::VectorXd r = residual(s, q, speed_norm);
    for (int iter = 0; iter < 12 && r.norm() > 1e-9; ++iter) {
      Eigen::MatrixXd jac(dim, dim);
      for (std::size_t k = 0; k < dim; ++k) {
        Eigen::VectorXd qk = q;
        const double h = 1e-7 * (1.0 + std::abs(q[static_cast<Eigen::Index>(k)]));
        qk[static_cast<Eigen::Index>(k)] += h;
        jac.col(static_cast<Eigen::Index>(k)) = (residual(s, qk, speed_norm) - r) / h;
      }
      const Eigen::VectorXd dq = jac.partialPivLu().solve(-r);
      double t = 1.0;
      for (int halvings = 0; halvings < 20; ++halvings) {  // backtracking: contacts saturate
        const Eigen::VectorXd trial = residual(s, q + t * dq, speed_norm);
        if (trial.norm() < r.norm()) break;
        t *= 0.5;
      }
      q += t * dq;
      r = residual(s, q, speed_norm);
      if ((t * dq).lpNorm<Eigen::Infinity>() < 1e-13) break;
    }
    for (std::size_t a = 0; a < 3; ++a) s.twist[a] = q[static_cast<Eigen::Index>(a)];
    for (std::size_t i = 0; i < m; ++i) s.phi_rate[i] = q[static_cast<Eigen::Index>(3 + i)];
    // Positions.
    const double yaw_mid = s.pose[2] + 0.5 * kStepS * s.twist[2];
    s.pose[0] += kStepS * (std::cos(yaw_mid) * s.twist[0] - std::sin(yaw_mid) * s.twist[1]);
    s.pose[1] += kStepS * (std::sin(yaw_mid) * s.twist[0] + std::cos(yaw_mid) * s.twist[1]);
    s.pose[2] += kStepS * s.twist[2];
    for (std::size_t i = 0; i < n_; ++i) {
      s.psi_rate[i] = s.wheel_set[i];  // the wheel's velocity loop holds its setpoint
      s.psi[i] += kStepS * s.psi_rate[i];
      // Along the heading the step's forces acted on (before the caster turns on).
      s.ground[i] = ground_speed(s, i);
      s.travel[i] += kStepS * s.ground[i];
      if (swpc_) {
        s.phi[i] += kStepS * s.phi_rate[i];
        s.phi_ref[i] += kStepS * s.steer_set[i];
      }
    }
  }

  [[nodiscard]] double ground_speed(const State& s, std::size_t i) const {
    const Contact& c = contacts_[i];
    const double phi = swpc_ ? s.phi[i] : 0.0;
    const double ux = std::cos(phi);
    const double uy = std::sin(phi);
    const double cx = c.px - c.trail * ux;
    const double cy = c.py - c.trail * uy;
    const double vx = s.twist[0] - s.twist[2] * cy;
    const double vy = s.twist[1] + s.twist[2] * cx;
    return ux * vx + uy * vy;
  }

 private:
  // Newton's residual: momentum of the body and of each steering axis, implicit Euler.
  [[nodiscard]] Eigen::VectorXd residual(const State& s, const Eigen::VectorXd& q,
                                         const std::vector<double>& speed_norm) const {
    const std::size_t m = swpc_ ? n_ : 0;
    Eigen::VectorXd out(3 + m);
    const double vx = q[0];
    const double vy = q[1];
    const double w = q[2];
    double fx_sum = 0;
    double fy_sum = 0;
    double moment = 0;
    const Truth& tr = spec_.truth;
    const double stiffness = tr.tyre_stiffness_per_load * load_;
    const double fmax = tr.friction_coefficient * load_;
    for (std::size_t i = 0; i < n_; ++i) {
      const Contact& c = contacts_[i];
      const double phi = swpc_ ? s.phi[i] : 0.0;
      const double phi_rate = swpc_ ? q[static_cast<Eigen::Index>(3 + i)] : 0.0;
      const double ux = std::cos(phi);
      const double uy = std::sin(phi);
      const double nx = -uy;
      const double ny = ux;
      const double cx = c.px - c.trail * ux;
      const double cy = c.py - c.trail * uy;
      const double vcx = vx - w * cy - c.trail * phi_rate * nx;
      const double vcy = vy + w * cx - c.trail * phi_rate * ny;
      const double ex = c.radius * s.wheel_set[i] - (ux * vcx + uy * vcy);
      const double ey = -(nx * vcx + ny * vcy);
      double flon = stiffness * ex / speed_norm[i];
      double flat = kLateralStiffnessShare * stiffness * ey / speed_norm[i];
      const double mag = std::hypot(flon, flat);
      if (mag > 1e-12) {
        const double k = fmax * std::tanh(mag / fmax) / mag;
        flon *= k;
        flat *= k;
      }
      const double fx = ux * flon + nx * flat;
      const double fy = uy * flon + ny * flat;
      fx_sum += fx;
      fy_sum += fy;
      moment += cx * fy - cy * fx;
      if (swpc_) {
        const double phi_next = s.phi[i] + kStepS * phi_rate;
        const double ref_next = s.phi_ref[i] + kStepS * s.steer_set[i];
        const double servo =
            kSteeringKp * (ref_next - phi_next) + kSteeringKd * (s.steer_set[i] - phi_rate);
        const double friction =
            tr.steering_friction_nm * std::tanh(phi_rate / kFrictionSmoothingRadps) +
            kSteeringViscous * phi_rate;
        // The contact force acts at -d u from the axis: torque -d times its lateral part.
        out[static_cast<Eigen::Index>(3 + i)] =
            kSteeringInertia * (phi_rate - s.phi_rate[i]) / kStepS -
            (servo - friction - c.trail * flat);
      }
    }
    out[0] = d_.mass_kg * ((vx - s.twist[0]) / kStepS - w * vy) - fx_sum;
    out[1] = d_.mass_kg * ((vy - s.twist[1]) / kStepS + w * vx) - fy_sum;
    out[2] = d_.yaw_inertia_kgm2 * (w - s.twist[2]) / kStepS - moment;
    return out;
  }

  const RunSpec& spec_;
  const Design& d_;
  std::size_t n_;
  bool swpc_ = false;
  std::vector<Contact> contacts_;
  double load_ = 0;
  double lin_limit_ = 0;
  double ang_limit_ = 0;
  double steer_limit_ = 0;
};

// The state at every tick, for sampling at the rows' times.
class History {
 public:
  explicit History(std::size_t n) : n_(n), width_(6 + 5 * n) {}
  void push(const State& s) {
    for (double v : s.pose) data_.push_back(v);
    for (double v : s.twist) data_.push_back(v);
    for (std::size_t i = 0; i < n_; ++i) data_.push_back(s.psi[i]);
    for (std::size_t i = 0; i < n_; ++i) data_.push_back(s.phi[i]);
    for (std::size_t i = 0; i < n_; ++i) data_.push_back(s.ground[i]);
    for (std::size_t i = 0; i < n_; ++i) data_.push_back(s.travel[i]);
    for (std::size_t i = 0; i < n_; ++i) data_.push_back(s.phi_ref[i] - s.phi[i]);
  }
  [[nodiscard]] std::size_t ticks() const { return data_.size() / width_; }
  /// Linear interpolation between ticks; t clamped to the recorded span.
  [[nodiscard]] std::vector<double> at(double t_s) const {
    // One tick recorded (the first step): nothing to interpolate.
    if (ticks() < 2) return {data_.begin(), data_.begin() + static_cast<std::ptrdiff_t>(width_)};
    const double x = std::clamp(t_s / kStepS, 0.0, static_cast<double>(ticks() - 1));
    const auto k = std::min(static_cast<std::size_t>(x), ticks() - 2);
    const double f = x - static_cast<double>(k);
    std::vector<double> out(width_);
    for (std::size_t j = 0; j < width_; ++j) {
      const double a = data_[k * width_ + j];
      const double b = data_[(k + 1) * width_ + j];
      out[j] = a + f * (b - a);
    }
    return out;
  }
  [[nodiscard]] static std::size_t psi(std::size_t i) { return 6 + i; }
  [[nodiscard]] std::size_t phi(std::size_t i) const { return 6 + n_ + i; }
  [[nodiscard]] std::size_t ground(std::size_t i) const { return 6 + 2 * n_ + i; }
  [[nodiscard]] std::size_t travel(std::size_t i) const { return 6 + 3 * n_ + i; }
  [[nodiscard]] std::size_t servo_error(std::size_t i) const { return 6 + 4 * n_ + i; }

 private:
  std::size_t n_;
  std::size_t width_;
  std::vector<double> data_;
};

// An incremental wheel encoder counts whole steps passed (rounds down: its zero is where it
// started, so only increments matter); an absolute steering encoder reports the code whose
// centre is nearest, so that its error has zero mean.
double quantize(double angle, double counts_per_rev) {
  return std::floor(angle * counts_per_rev / (2 * kPi)) * 2 * kPi / counts_per_rev;
}
double quantize_nearest(double angle, double counts_per_rev) {
  return std::round(angle * counts_per_rev / (2 * kPi)) * 2 * kPi / counts_per_rev;
}

void check(const RunSpec& spec) {
  if (!(spec.row_rate_hz >= 20.0 && spec.row_rate_hz <= 100.0)) {
    throw std::invalid_argument("row rate " + std::to_string(spec.row_rate_hz) +
                                " Hz: outside [20, 100]");
  }
  if (!(spec.duration_s >= 10.0 && spec.duration_s <= 600.0)) {
    throw std::invalid_argument("duration " + std::to_string(spec.duration_s) +
                                " s: outside [10, 600]");
  }
  const Truth& t = spec.truth;
  if (!(t.tyre_stiffness_per_load > 0) || !(t.friction_coefficient > 0)) {
    throw std::invalid_argument("tyre: stiffness and friction must be positive");
  }
  if (t.sensor_delay_s < 0 || t.sensor_delay_s > 0.5 || t.mocap_latency_s < 0 ||
      t.mocap_latency_s > 0.5 || t.actuator_lag_s < 0 || t.actuator_lag_s > 1 ||
      t.steering_lag_s < 0 || t.steering_lag_s > 1) {
    throw std::invalid_argument("delays and lags must be within [0, 0.5] s (lags [0, 1] s)");
  }
  if (!(t.mocap_clock_rate >= 0.0 && t.mocap_clock_rate <= 0.01)) {
    throw std::invalid_argument("mocap clock rate " + std::to_string(t.mocap_clock_rate) +
                                ": outside [0, 0.01]");
  }
}

}  // namespace

std::vector<Row> simulate(const RunSpec& spec) {
  return simulate_commanded(spec, nullptr, nullptr);
}

std::vector<double> friction_limit_servo_errors_rad(const RunSpec& spec) {
  const Design d = design(spec.design);
  if (d.drive != Drive::kSwpc) return {};
  const Truth& t = spec.truth;
  const double load = d.mass_kg * kGravity / static_cast<double>(d.modules.size());
  std::vector<double> out;
  for (std::size_t i = 0; i < d.modules.size(); ++i) {
    const double scale = i < t.caster_offset_scale.size() ? t.caster_offset_scale[i] : 1.0;
    out.push_back(d.modules[i].caster_offset_m * scale * t.friction_coefficient * load /
                  kSteeringKp);
  }
  return out;
}

std::vector<Row> simulate_commanded(const RunSpec& spec, const std::vector<double>* commands,
                                    std::vector<double>* used) {
  check(spec);
  const Design d = design(spec.design);
  const Robot robot(spec, d);
  const std::size_t n = robot.n();
  const bool swpc = d.drive == Drive::kSwpc;
  const Truth& tr = spec.truth;
  // A geared encoder: the model states the real-valued counts, and the encoder has them.
  const double gear = spec.model.fractional_counts ? kFractionalGear : 1.0;
  const double wheel_counts = d.wheel_counts_per_rev * gear;
  const double steer_counts = d.steering_counts_per_rev * gear;

  Stream start_rng(spec.seed, kStartStream);
  State s;
  s.pose[0] = start_rng.uniform(-1.0, 1.0);
  s.pose[1] = start_rng.uniform(-1.0, 1.0);
  s.pose[2] = start_rng.uniform(-kPi, kPi);
  for (auto* v : {&s.psi, &s.psi_rate, &s.phi, &s.phi_rate, &s.phi_ref, &s.wheel_set, &s.steer_set,
                  &s.ground, &s.travel}) {
    v->assign(n, 0.0);
  }
  for (std::size_t i = 0; swpc && i < n; ++i) {  // casters left roughly forward
    s.phi[i] = start_rng.uniform(-0.3, 0.3);
    s.phi_ref[i] = s.phi[i];
  }
  const double start_pose[3] = {s.pose[0], s.pose[1], s.pose[2]};
  Planner planner(d, spec.script, spec.seed, start_pose, spec.duration_s);

  History history(n);
  history.push(s);
  std::vector<double> plan_cmd;  // per planner period: vx, vy, wz
  const auto ticks = static_cast<std::size_t>(std::ceil((spec.duration_s + 0.5) / kStepS));
  const auto plan_every = static_cast<std::size_t>(std::lround(Planner::kPeriodS / kStepS));
  std::vector<double> measured(n, 0.0);
  for (std::size_t k = 0; k < ticks; ++k) {
    const double t = static_cast<double>(k) * kStepS;
    if (k % plan_every == 0) {
      planner.update(t, s.pose);
      const std::size_t period = plan_cmd.size() / 3;
      for (std::size_t a = 0; a < 3; ++a) {
        plan_cmd.push_back(commands != nullptr && 3 * period + a < commands->size()
                               ? (*commands)[3 * period + a]
                               : planner.command()[a]);
      }
    }
    if (swpc) {  // the controller reads the steering encoders, as late as they report
      const std::vector<double> then = history.at(t - tr.sensor_delay_s);
      for (std::size_t i = 0; i < n; ++i) {
        measured[i] =
            quantize_nearest(then[history.phi(i)] - robot.contact(i).offset, steer_counts);
      }
    }
    robot.control(s, &plan_cmd[plan_cmd.size() - 3], measured);
    robot.step(s);
    history.push(s);
  }

  // Rows: the recorder's clock, the sensors and the motion capture.
  Stream sensor_rng(spec.seed, kSensorStream);
  Stream clock_rng(spec.seed, kClockStream);
  Stream mocap_rng(spec.seed, kMocapStream);
  const double noise = spec.noise ? 1.0 : 0.0;
  const double mocap_period = 1.0 / d.mocap_rate_hz;
  double next_frame = mocap_rng.uniform(0.0, mocap_period);
  std::vector<Row> rows;
  double previous_t = -1.0;
  for (std::size_t j = 0;; ++j) {
    double t = static_cast<double>(j) / spec.row_rate_hz;
    t += noise * std::clamp(0.0001 * clock_rng.normal(), -0.0004, 0.0004);
    if (t > spec.duration_s) break;
    t = std::max(t, 0.0);
    Row row;
    row.t_s = t;
    const auto plan_index =
        std::min(static_cast<std::size_t>(t / Planner::kPeriodS + 1e-9), plan_cmd.size() / 3 - 1);
    for (std::size_t a = 0; a < 3; ++a) row.cmd[a] = plan_cmd[3 * plan_index + a];
    const std::vector<double> now = history.at(t);
    const std::vector<double> late = history.at(t - tr.sensor_delay_s);
    for (int a = 0; a < 3; ++a) {
      row.pose[a] = now[static_cast<std::size_t>(a)];
      row.twist[a] = now[3 + static_cast<std::size_t>(a)];
    }
    for (std::size_t i = 0; i < n; ++i) {
      row.true_wheel_rad.push_back(now[History::psi(i)]);
      row.wheel_rad.push_back(quantize(late[History::psi(i)], wheel_counts));
      row.contact_speed_mps.push_back(now[history.ground(i)]);
      row.contact_travel_m.push_back(now[history.travel(i)]);
      if (swpc) row.steering_servo_error_rad.push_back(now[history.servo_error(i)]);
      if (swpc) {
        row.true_steer_rad.push_back(now[history.phi(i)]);
        row.steer_rad.push_back(
            wrap(quantize_nearest(late[history.phi(i)] - robot.contact(i).offset, steer_counts)));
      }
    }
    row.gyro_radps = tr.gyro_scale * late[5] + tr.gyro_bias_rad_s +
                     noise * d.gyro_noise_rad_s * sensor_rng.normal();
    // A motion-capture frame that arrived since the previous row, showing the marker as it
    // was the latency earlier.
    bool frame = false;
    while (next_frame <= t) {
      if (next_frame > previous_t) frame = true;
      next_frame += mocap_period;
    }
    if (frame && !mocap_rng.chance(kMocapLossProbability)) {
      const std::vector<double> seen = history.at(t - tr.mocap_latency_s - tr.mocap_clock_rate * t);
      const double c = std::cos(seen[2]);
      const double sn = std::sin(seen[2]);
      row.has_mocap = true;
      row.mocap[0] = seen[0] + c * tr.marker_x_m - sn * tr.marker_y_m +
                     noise * d.mocap_position_noise_m * mocap_rng.normal();
      row.mocap[1] = seen[1] + sn * tr.marker_x_m + c * tr.marker_y_m +
                     noise * d.mocap_position_noise_m * mocap_rng.normal();
      row.mocap[2] =
          wrap(seen[2] + tr.marker_yaw_rad + noise * d.mocap_yaw_noise_rad * mocap_rng.normal());
    }
    previous_t = t;
    rows.push_back(std::move(row));
  }
  if (used != nullptr) *used = plan_cmd;
  return rows;
}

}  // namespace swivel::second
