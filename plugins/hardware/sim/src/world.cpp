// SPDX-License-Identifier: Apache-2.0
#include "swivel/sim/world.hpp"

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <stdexcept>

#include "swivel/differential/differential_kinematics.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"

namespace swivel::sim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Longest single step() accepted; guards the sub-step count against absurd inputs.
constexpr double kMaxStepS = 3600.0;
// Time comparisons tolerate accumulated rounding of the sub-step sum.
constexpr double kTimeEpsS = 1e-9;

double wrap_angle(double a) noexcept {
  a = std::remainder(a, kTwoPi);
  return a <= -std::numbers::pi ? a + kTwoPi : a;
}

// SplitMix64: decorrelates the seeds of the separate random streams.
std::uint64_t mix_seed(std::uint64_t x) noexcept {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27U)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31U);
}

Pose2 compose(const Pose2& a, const Pose2& b) noexcept {
  const double c = std::cos(a.yaw_rad);
  const double s = std::sin(a.yaw_rad);
  return Pose2{a.x_m + c * b.x_m - s * b.y_m, a.y_m + s * b.x_m + c * b.y_m,
               wrap_angle(a.yaw_rad + b.yaw_rad)};
}

bool finite(double v) noexcept { return std::isfinite(v); }

}  // namespace

World::World(const RobotModel& true_model, const SimOptions& options)
    : plant_(resolve_plant(true_model)), options_(options) {
  if (!(options_.substep_s > 0.0) || options_.substep_s > 0.1) {
    throw std::invalid_argument("substep_s must be in (0, 0.1] s");
  }
  const NonSystematicErrors& ns = options_.nonsystematic;
  if (!(ns.wheel_slip_std >= 0.0) || !(ns.lateral_scrub_std >= 0.0) ||
      !(ns.correlation_time_s > 0.0)) {
    throw std::invalid_argument(
        "non-systematic errors: standard deviations must be >= 0 and the correlation time > 0");
  }
  validate_caster_forces(options_.caster_forces);
  if (!(plant_.sensors.motion_capture.rate_hz > 0.0)) {
    throw std::invalid_argument("motion capture rate must be positive");
  }
  n_ = plant_.module_count;
  pose_ = options_.start_pose;
  pose_.yaw_rad = wrap_angle(pose_.yaw_rad);
  yaw_unwrapped_rad_ = options_.start_pose.yaw_rad;
  for (std::size_t i = 0; i < n_; ++i) {
    if (plant_.drivetrain == DrivetrainKind::kSwpc) {
      modules_[i].phi_rad = options_.initial_steer_rad[i];
      modules_[i].servo_ref_rad = options_.initial_steer_rad[i];
    }
  }
  sensor_rng_.seed(mix_seed(options_.seed));
  process_rng_.seed(mix_seed(options_.seed ^ 0x5EEDULL));
  // Start the random processes in their stationary distribution.
  for (std::size_t i = 0; i < n_; ++i) {
    modules_[i].slip_state = ns.wheel_slip_std * gaussian(process_rng_);
  }
  scrub_state_ = ns.lateral_scrub_std * gaussian(process_rng_);

  mocap_period_s_ = 1.0 / plant_.sensors.motion_capture.rate_hz;
  if (options_.motion_capture) {
    // A sample at t = 0, like every later multiple of the period.
    mocap_next_index_ = 0;
    mocap_pending_ = MotionCaptureSample{};
  }
  if (plant_.sensor_delay_s > 0.0) {
    history_spacing_s_ = 0.5 * options_.substep_s;
    const auto capacity =
        static_cast<std::size_t>(std::ceil(plant_.sensor_delay_s / history_spacing_s_)) + 4;
    history_.resize(capacity);
  }
  record_history();
  if (options_.motion_capture) {
    // Sample at t = 0 so that a log starts with a pose.
    substep(0.0, ActuatorCommand{});
  }
}

double World::gaussian(std::mt19937_64& rng) noexcept {
  // Box-Muller without a cached second value, so each stream's sequence depends only on
  // how many numbers it has produced.
  constexpr double kScale = 1.0 / 9007199254740992.0;                    // 2^-53
  const double u1 = (static_cast<double>(rng() >> 11U) + 1.0) * kScale;  // (0, 1]
  const double u2 = static_cast<double>(rng() >> 11U) * kScale;          // [0, 1)
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
}

double World::quantize(double angle_rad, double counts_per_rev) const noexcept {
  if (!options_.quantize_encoders || !(counts_per_rev > 0.0)) return angle_rad;
  const double q = kTwoPi / counts_per_rev;
  return std::floor(angle_rad / q + 0.5) * q;
}

Status World::step(double dt_s, const ActuatorCommand& command) noexcept {
  if (!finite(dt_s) || dt_s < 0.0 || dt_s > kMaxStepS) {
    last_error_ = "sim: time step is negative, too long or not finite";
    return Status::kError;
  }
  if (command.module_count != n_) {
    last_error_ = "sim: command module count differs from the robot's";
    return Status::kError;
  }
  for (std::size_t i = 0; i < n_; ++i) {
    if (!finite(command.wheel_rate_radps[i]) || !finite(command.steer_rate_radps[i])) {
      last_error_ = "sim: non-finite actuator setpoint";
      return Status::kError;
    }
    const auto mode = static_cast<std::uint8_t>(command.mode[i]);
    if (mode > static_cast<std::uint8_t>(ModuleDriveMode::kTorque)) {
      last_error_ = "sim: unknown module drive mode";
      return Status::kError;
    }
  }
  if (dt_s == 0.0) return Status::kOk;
  const auto count = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(std::ceil(dt_s / options_.substep_s - 1e-9)));
  const double h = dt_s / static_cast<double>(count);
  for (std::int64_t k = 0; k < count; ++k) substep(h, command);
  return Status::kOk;
}

void World::substep(double h, const ActuatorCommand& command) noexcept {
  if (h > 0.0) {
    const bool swpc = plant_.drivetrain == DrivetrainKind::kSwpc;
    const double tau = plant_.actuator_time_constant_s;
    const double follow = tau > 0.0 ? 1.0 - std::exp(-h / tau) : 1.0;
    const double tau_steer = plant_.steering_time_constant_s;
    const double follow_steer = tau_steer > 0.0 ? 1.0 - std::exp(-h / tau_steer) : 1.0;
    const NonSystematicErrors& ns = options_.nonsystematic;
    const double decay = std::exp(-h / ns.correlation_time_s);
    const double drive = std::sqrt(std::max(0.0, 1.0 - decay * decay));
    bool all_velocity = true;
    for (std::size_t i = 0; i < n_; ++i)
      all_velocity = all_velocity && command.mode[i] == ModuleDriveMode::kVelocity;
    const bool forces = swpc && all_velocity && options_.caster_forces.steering_yield_rad > 0.0;

    std::array<double, kMaxModules> ground{};
    for (std::size_t i = 0; i < n_; ++i) {
      ModuleState& m = modules_[i];
      const ModuleDriveMode mode = command.mode[i];
      const double before = m.wheel_rate_radps;
      if (mode == ModuleDriveMode::kLocked) {
        // The jig holds the wheel: no lag, no slip.
        m.wheel_rate_radps = 0.0;
        m.steer_rate_radps = 0.0;
        ground[i] = 0.0;
        continue;
      }
      m.wheel_rate_radps += follow * (command.wheel_rate_radps[i] - m.wheel_rate_radps);
      if (mode == ModuleDriveMode::kVelocity) {
        double& rate = forces ? m.servo_rate_radps : m.steer_rate_radps;
        rate += follow_steer * (command.steer_rate_radps[i] - rate);
      }
      const double accel = (m.wheel_rate_radps - before) / h;
      double g =
          m.wheel_rate_radps - plant_.slip_gain_per_radps2 * std::abs(m.wheel_rate_radps) * accel;
      if (ns.wheel_slip_std > 0.0) {
        m.slip_state = decay * m.slip_state + drive * ns.wheel_slip_std * gaussian(process_rng_);
        g *= 1.0 + m.slip_state;
      }
      ground[i] = g;
    }

    Twist2 t;
    if (forces) {
      // The casters turn as the body's motion lets them: it is needed even where the body
      // does not move.
      t = caster_force_twist(h, ground.data());
    } else if (!options_.move_body && all_velocity) {
      // Actuators only: the body stays where it is.
    } else if (swpc) {
      t = swpc_twist(command, ground.data());
    } else {
      const differential::WheelRates rates{ground[0], ground[1]};
      t = differential::forward(effective_differential(plant_, ground[0], ground[1]), rates);
      if (command.mode[0] == ModuleDriveMode::kLocked ||
          command.mode[1] == ModuleDriveMode::kLocked) {
        // One wheel held: the robot pivots about it (the other wheel's arc sets the rate).
        const double b = plant_.differential.track_width_m;
        if (command.mode[0] == ModuleDriveMode::kLocked &&
            command.mode[1] == ModuleDriveMode::kLocked) {
          t = Twist2{};
        } else if (command.mode[0] == ModuleDriveMode::kLocked) {
          const double v = plant_.differential.wheel_radius_right_m * ground[1];
          t = Twist2{0.5 * v, 0.0, v / b};
        } else {
          const double v = plant_.differential.wheel_radius_left_m * ground[0];
          t = Twist2{0.5 * v, 0.0, -v / b};
        }
      }
    }
    if (ns.lateral_scrub_std > 0.0) {
      scrub_state_ = decay * scrub_state_ + drive * ns.lateral_scrub_std * gaussian(process_rng_);
      // Perpendicular to the body velocity, proportional to the speed.
      const double vx = t.vx_mps;
      const double vy = t.vy_mps;
      t.vx_mps -= scrub_state_ * vy;
      t.vy_mps += scrub_state_ * vx;
    }
    twist_ = t;

    // What each encoder sees: the wheel's own rate, or for a torque-driven wheel the rate at
    // which it rolls without slipping (contact point's speed along the wheel over the radius).
    std::array<double, kMaxModules> encoder_rate{};
    for (std::size_t i = 0; i < n_; ++i) encoder_rate[i] = modules_[i].wheel_rate_radps;
    if (forces) {
      for (std::size_t i = 0; i < n_; ++i) {
        ModuleState& m = modules_[i];
        m.phi_rad += m.steer_rate_radps * h;
        m.servo_ref_rad += m.servo_rate_radps * h;
      }
    } else if (swpc) {
      for (std::size_t i = 0; i < n_; ++i) {
        ModuleState& m = modules_[i];
        const ModuleDriveMode mode = command.mode[i];
        if (mode == ModuleDriveMode::kFreeSteer || mode == ModuleDriveMode::kTorque) {
          // No lateral slip of the contact point: the caster turns into its direction of
          // travel.
          const SwpcModuleParams& p = plant_.modules[i];
          double vsx = 0.0;
          double vsy = 0.0;
          swpc::steering_axis_velocity(p, t, vsx, vsy);
          const double c = std::cos(m.phi_rad);
          const double s = std::sin(m.phi_rad);
          m.steer_rate_radps = (-s * vsx + c * vsy) / p.caster_offset_m - t.wz_radps;
          if (mode == ModuleDriveMode::kTorque) {
            encoder_rate[i] = (c * vsx + s * vsy) / p.wheel_radius_m;
          }
        }
        m.phi_rad += m.steer_rate_radps * h;
      }
    }
    for (std::size_t i = 0; i < n_; ++i) modules_[i].psi_rad += encoder_rate[i] * h;
    if (options_.move_body || !all_velocity) {
      const Pose2 delta = swpc::integrate_twist(t, h);
      pose_ = compose(pose_, delta);
      yaw_unwrapped_rad_ += delta.yaw_rad;
    }
    t_s_ += h;
    if (history_spacing_s_ > 0.0) record_history();
  }

  if (options_.motion_capture &&
      t_s_ + kTimeEpsS >= static_cast<double>(mocap_next_index_) * mocap_period_s_) {
    const MotionCaptureParams& mc = plant_.sensors.motion_capture;
    MotionCaptureSample s;
    s.valid = true;
    s.stamp_s = t_s_;
    s.pose = pose_;
    if (options_.sensor_noise) {
      s.pose.x_m += mc.position_noise_m * gaussian(sensor_rng_);
      s.pose.y_m += mc.position_noise_m * gaussian(sensor_rng_);
      s.pose.yaw_rad = wrap_angle(s.pose.yaw_rad + mc.yaw_noise_rad * gaussian(sensor_rng_));
    }
    mocap_pending_ = s;
    mocap_next_index_ =
        static_cast<std::uint64_t>(std::floor((t_s_ + kTimeEpsS) / mocap_period_s_)) + 1;
  }
}

Twist2 World::caster_force_twist(double h, const double* ground) noexcept {
  std::array<CasterState, kMaxModules> casters{};
  std::array<double, kMaxModules> rates{};
  // Started where the last two sub-steps' motion leads (it changes smoothly between them).
  for (std::size_t i = 0; i < n_; ++i) {
    const ModuleState& m = modules_[i];
    casters[i] = CasterState{m.phi_rad, m.servo_ref_rad, m.servo_rate_radps, ground[i]};
    rates[i] = 2.0 * m.steer_rate_radps - m.previous_steer_rate_radps;
  }
  Twist2 t{2.0 * twist_.vx_mps - previous_twist_.vx_mps,
           2.0 * twist_.vy_mps - previous_twist_.vy_mps,
           2.0 * twist_.wz_radps - previous_twist_.wz_radps};
  if (!caster_force_step(options_.caster_forces,
                         std::span<const SwpcModuleParams>(plant_.modules.data(), n_),
                         std::span<const CasterState>(casters.data(), n_), h, twist_, t,
                         std::span<double>(rates.data(), n_))) {
    ++caster_force_failures_;
  }
  previous_twist_ = twist_;
  for (std::size_t i = 0; i < n_; ++i) {
    modules_[i].previous_steer_rate_radps = modules_[i].steer_rate_radps;
    modules_[i].steer_rate_radps = rates[i];
  }
  return t;
}

Twist2 World::swpc_twist(const ActuatorCommand& command, const double* ground) noexcept {
  std::array<double, kMaxModules> phi{};
  std::array<double, kMaxModules> steer{};
  std::size_t locked = 0;
  std::size_t locked_index = 0;
  bool all_velocity = true;
  for (std::size_t i = 0; i < n_; ++i) {
    phi[i] = modules_[i].phi_rad;
    steer[i] = modules_[i].steer_rate_radps;
    if (command.mode[i] != ModuleDriveMode::kVelocity) all_velocity = false;
    if (command.mode[i] == ModuleDriveMode::kLocked) {
      ++locked;
      locked_index = i;
    }
  }
  const std::span<const SwpcModuleParams> geometry(plant_.modules.data(), n_);
  if (all_velocity) {
    const swpc::ForwardResult r = swpc::forward(geometry, std::span<const double>(phi.data(), n_),
                                                std::span<const double>(steer.data(), n_),
                                                std::span<const double>(ground, n_));
    return r.ok ? r.twist : Twist2{};
  }
  if (locked > 1) return Twist2{};  // two fixed contact points: the robot cannot move

  // Equations a . (vx, vy, w) = b: a rolling row for every moving module, a lateral row for
  // every steered one; a free caster's lateral equation only fixes its own steering rate.
  using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::ColMajor, 2 * kMaxModules, 3>;
  using Rhs = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 2 * kMaxModules, 1>;
  Rows a(static_cast<Eigen::Index>(2 * n_), 3);
  Rhs b(static_cast<Eigen::Index>(2 * n_));
  Eigen::Index rows = 0;
  for (std::size_t i = 0; i < n_; ++i) {
    if (command.mode[i] == ModuleDriveMode::kLocked) continue;
    const SwpcModuleParams& m = plant_.modules[i];
    const double c = std::cos(phi[i]);
    const double s = std::sin(phi[i]);
    a.row(rows) << c, s, m.x_m * s - m.y_m * c;
    b(rows++) = m.wheel_radius_m * ground[i];
    if (command.mode[i] == ModuleDriveMode::kVelocity) {
      a.row(rows) << -s, c, m.x_m * c + m.y_m * s - m.caster_offset_m;
      b(rows++) = m.caster_offset_m * steer[i];
    }
  }
  const auto used_a = a.topRows(rows);
  const auto used_b = b.head(rows);
  if (locked == 1) {
    // Rotation about the locked contact point c: (vx, vy, w) = w (c_y, -c_x, 1).
    const SwpcModuleParams& m = plant_.modules[locked_index];
    const double cx = m.x_m - m.caster_offset_m * std::cos(phi[locked_index]);
    const double cy = m.y_m - m.caster_offset_m * std::sin(phi[locked_index]);
    const Eigen::Vector3d dir(cy, -cx, 1.0);
    Rhs column = used_a * dir;
    const double norm2 = column.squaredNorm();
    if (!(norm2 > 1e-18)) return Twist2{};
    const double w = column.dot(used_b) / norm2;
    return Twist2{w * cy, -w * cx, w};
  }
  // Least squares through the normal equations; a pseudo-inverse keeps under-determined
  // cases (e.g. two free casters) finite.
  const Eigen::Matrix3d ata = used_a.transpose() * used_a;
  const Eigen::Vector3d atb = used_a.transpose() * used_b;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(ata);
  const Eigen::Vector3d& values = eig.eigenvalues();
  const double cutoff = 1e-12 * std::max(values.maxCoeff(), 1e-300);
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    if (values(k) > cutoff) {
      const Eigen::Vector3d v = eig.eigenvectors().col(k);
      x += v * (v.dot(atb) / values(k));
    }
  }
  return Twist2{x(0), x(1), x(2)};
}

void World::record_history() noexcept {
  if (history_.empty()) return;
  if (history_size_ > 0) {
    const std::size_t newest = (history_head_ + history_size_ - 1) % history_.size();
    if (t_s_ - history_[newest].t_s < history_spacing_s_ - kTimeEpsS) return;
  }
  std::size_t slot = 0;
  if (history_size_ < history_.size()) {
    slot = (history_head_ + history_size_) % history_.size();
    ++history_size_;
  } else {
    slot = history_head_;
    history_head_ = (history_head_ + 1) % history_.size();
  }
  SensorSample& s = history_[slot];
  s.t_s = t_s_;
  s.yaw_rad = yaw_unwrapped_rad_;
  for (std::size_t i = 0; i < n_; ++i) {
    s.psi_rad[i] = modules_[i].psi_rad;
    s.phi_rad[i] = modules_[i].phi_rad;
  }
}

void World::sensor_sample_at(double t_s, SensorSample& out) const noexcept {
  out.t_s = t_s_;
  out.yaw_rad = yaw_unwrapped_rad_;
  for (std::size_t i = 0; i < n_; ++i) {
    out.psi_rad[i] = modules_[i].psi_rad;
    out.phi_rad[i] = modules_[i].phi_rad;
  }
  if (history_size_ == 0 || t_s >= t_s_) return;
  const auto at = [this](std::size_t k) -> const SensorSample& {
    return history_[(history_head_ + k) % history_.size()];
  };
  if (t_s <= at(0).t_s) {
    out = at(0);
    return;
  }
  // Newest recorded sample at or before t_s (samples are in time order).
  std::size_t lo = 0;
  std::size_t hi = history_size_;
  while (hi - lo > 1) {
    const std::size_t mid = (lo + hi) / 2;
    if (at(mid).t_s <= t_s) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  const SensorSample& a = at(lo);
  const SensorSample b = lo + 1 < history_size_ ? at(lo + 1) : out;  // out holds "now"
  const double span = b.t_s - a.t_s;
  const double f = span > 0.0 ? (t_s - a.t_s) / span : 0.0;
  out.t_s = t_s;
  out.yaw_rad = a.yaw_rad + f * (b.yaw_rad - a.yaw_rad);
  for (std::size_t i = 0; i < n_; ++i) {
    out.psi_rad[i] = a.psi_rad[i] + f * (b.psi_rad[i] - a.psi_rad[i]);
    out.phi_rad[i] = a.phi_rad[i] + f * (b.phi_rad[i] - a.phi_rad[i]);
  }
}

double World::steer_reading_rad(std::size_t i) const noexcept {
  if (i >= n_ || plant_.drivetrain != DrivetrainKind::kSwpc) return 0.0;
  SensorSample s;
  sensor_sample_at(t_s_ - plant_.sensor_delay_s, s);
  return quantize(s.phi_rad[i] - plant_.modules[i].steering_offset_rad,
                  plant_.sensors.steering_encoder_counts_per_rev);
}

double World::sensed_steer_rad(std::size_t i) const noexcept {
  if (i >= n_ || plant_.drivetrain != DrivetrainKind::kSwpc) return 0.0;
  SensorSample s;
  sensor_sample_at(t_s_ - plant_.sensor_delay_s, s);
  return s.phi_rad[i];
}

void World::turn_steering(std::size_t i, double delta_rad) noexcept {
  if (i >= n_ || !std::isfinite(delta_rad)) return;
  modules_[i].phi_rad += delta_rad;
  modules_[i].servo_ref_rad += delta_rad;
  for (std::size_t k = 0; k < history_size_; ++k) {
    history_[(history_head_ + k) % history_.size()].phi_rad[i] += delta_rad;
  }
}

void World::read(HardwareState& out) noexcept {
  SensorSample s;
  sensor_sample_at(t_s_ - plant_.sensor_delay_s, s);
  out.stamp_s = t_s_;
  out.module_count = static_cast<std::uint32_t>(n_);
  const bool swpc = plant_.drivetrain == DrivetrainKind::kSwpc;
  for (std::size_t i = 0; i < kMaxModules; ++i) {
    out.wheel_angle_rad[i] = 0.0;
    out.steer_angle_rad[i] = 0.0;
  }
  for (std::size_t i = 0; i < n_; ++i) {
    out.wheel_angle_rad[i] = quantize(s.psi_rad[i], plant_.sensors.wheel_encoder_counts_per_rev);
    if (swpc) {
      out.steer_angle_rad[i] = quantize(s.phi_rad[i] - plant_.modules[i].steering_offset_rad,
                                        plant_.sensors.steering_encoder_counts_per_rev);
    }
  }
  double rate = twist_.wz_radps;
  if (have_read_ && t_s_ - last_read_t_s_ > kTimeEpsS) {
    rate = (s.yaw_rad - last_read_yaw_rad_) / (t_s_ - last_read_t_s_);
  }
  have_read_ = true;
  last_read_t_s_ = t_s_;
  last_read_yaw_rad_ = s.yaw_rad;
  const GyroParams& g = plant_.sensors.gyro;
  double gyro = g.scale * rate + g.bias_rad_s;
  if (options_.sensor_noise && g.noise_rad_s > 0.0) gyro += g.noise_rad_s * gaussian(sensor_rng_);
  out.gyro_wz_radps = gyro;
  out.gyro_valid = true;
  out.motion_capture = mocap_pending_;
  mocap_pending_.valid = false;
}

Pose2 World::contact_point_world(std::size_t i) const noexcept {
  Pose2 local;
  if (plant_.drivetrain == DrivetrainKind::kSwpc) {
    const SwpcModuleParams& m = plant_.modules[i];
    local.x_m = m.x_m - m.caster_offset_m * std::cos(modules_[i].phi_rad);
    local.y_m = m.y_m - m.caster_offset_m * std::sin(modules_[i].phi_rad);
  } else {
    local.y_m = (i == 0 ? 0.5 : -0.5) * plant_.differential.track_width_m;
  }
  return compose(pose_, local);
}

}  // namespace swivel::sim
