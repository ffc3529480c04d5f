#include "swivel/model_gap/replay.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <stdexcept>

#include "swivel/differential/differential_kinematics.hpp"
#include "swivel/localization/eg_odometry.hpp"
#include "swivel/sim/effects.hpp"
#include "swivel/sim/open_loop.hpp"
#include "swivel/sim/world.hpp"
#include "swivel/swpc/swpc_kinematics.hpp"

namespace swivel::model_gap {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Integration step of the re-simulation. The differential replay is cheap and keeps the
// simulator's default; the swpc one runs hundreds of times per fit and uses a coarser step
// (commands are ramps at the log rate, so the difference stays near the sensor noise; it
// lengthens a fitted actuator lag by a few milliseconds).
constexpr double kDifferentialSubstepS = 0.001;
constexpr double kSwpcSubstepS = 0.0025;

// Typical magnitude of each effect parameter: the fit works in units of it, and it sets the
// finite-difference step. Keys are the simulator's (sim::effect_library).
double typical_magnitude(const std::string& effect) {
  if (effect == "gyro_bias") return 0.005;        // rad/s
  if (effect == "steering_offset") return 0.02;   // rad
  if (effect == "slip") return 0.002;             // per rad/s^2
  if (effect == "actuator_lag") return 0.05;      // s
  if (effect == "sensor_latency") return 0.02;    // s
  if (effect == "caster_offset") return 0.1;      // factor
  return 0.01;  // scale factors: gyro_scale, wheel_radius, track_width
}

// 1/2 w |w|: its change over a step is the integral of |w| dw/dt, the slip of sim/effects.hpp.
double half_signed_square(double w) { return 0.5 * w * std::abs(w); }

}  // namespace

struct Replay::Impl {
  RobotModel nominal;
  std::size_t n = 0;
  std::size_t modules = 2;
  bool swpc = false;
  std::vector<double> t;
  std::vector<Twist2> cmd;
  std::vector<std::vector<double>> wheel;  // measured, [module][k]
  std::vector<std::vector<double>> steer;
  std::vector<double> gyro;
  std::vector<std::vector<double>> slip_h;  // half_signed_square of the smoothed wheel rate
  Pose2 start;
  ChannelSet measured;
  // Channel indices.
  std::size_t dr_x = 0, dr_y = 0, dr_yaw = 0, sim_x = 0, sim_y = 0, sim_yaw = 0, sim_gyro = 0;
  std::vector<std::size_t> sim_wheel, sim_steer;
  // Scratch for dead reckoning before the latency shift.
  mutable std::vector<double> dr_px, dr_py, dr_pyaw;

  void dead_reckon(const sim::PlantParams& plant, ChannelSet& out, std::size_t end) const;
  void resimulate(const RobotModel& model, const sim::PlantParams& plant, ChannelSet& out,
                  std::size_t end) const;
};

Replay::Replay(const RobotModel& nominal, const RunData& run) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  if (run.drivetrain != nominal.drivetrain) {
    throw std::invalid_argument("run " + run.source + " is from a " +
                                (run.drivetrain == DrivetrainKind::kSwpc ? "swpc" : "differential") +
                                " robot but model " + nominal.source_file + " is not");
  }
  if (run.module_count != nominal.module_count()) {
    throw std::invalid_argument("run " + run.source + " has " + std::to_string(run.module_count) +
                                " modules but model " + nominal.source_file + " has " +
                                std::to_string(nominal.module_count()));
  }
  if (run.size() < 10) {
    throw std::invalid_argument("run " + run.source + " has " + std::to_string(run.size()) +
                                " samples; the workflow needs at least 10");
  }
  d.nominal = nominal;
  d.n = run.size();
  d.modules = run.module_count;
  d.swpc = run.drivetrain == DrivetrainKind::kSwpc;
  d.t = run.t_s;
  d.cmd.resize(d.n);
  for (std::size_t k = 0; k < d.n; ++k) {
    d.cmd[k] = Twist2{run.cmd_vx_mps[k], run.cmd_vy_mps[k], run.cmd_wz_radps[k]};
  }
  d.wheel = run.wheel_rad;
  d.steer = run.steer_rad;
  d.gyro = run.gyro_radps;
  // Start pose: motion capture averaged while the robot stands still at the start (up to
  // 1 s), so that one noisy sample does not tilt every replayed trajectory.
  double sx = 0.0;
  double sy = 0.0;
  double syaw = 0.0;
  double count = 0.0;
  for (std::size_t k = 0; k < d.n; ++k) {
    const bool moving = d.cmd[k].vx_mps != 0.0 || d.cmd[k].vy_mps != 0.0 || d.cmd[k].wz_radps != 0.0;
    if (count > 0.0 && (moving || d.t[k] - d.t[0] > 1.0)) break;
    if (!std::isfinite(run.truth_x_m[k])) continue;
    sx += run.truth_x_m[k];
    sy += run.truth_y_m[k];
    syaw += run.truth_yaw_rad[k];
    count += 1.0;
    if (moving) break;
  }
  const bool have_start = count > 0.0;
  if (have_start) d.start = Pose2{sx / count, sy / count, syaw / count};
  if (!have_start) {
    throw std::invalid_argument("run " + run.source +
                                " has no motion-capture samples: nothing to compare poses with");
  }
  // Smoothed wheel rates (centred over +-2 samples) keep encoder quantization out of the
  // slip correction.
  d.slip_h.assign(d.modules, std::vector<double>(d.n, 0.0));
  for (std::size_t i = 0; i < d.modules; ++i) {
    for (std::size_t k = 0; k < d.n; ++k) {
      const std::size_t lo = k >= 2 ? k - 2 : 0;
      const std::size_t hi = std::min(d.n - 1, k + 2);
      const double dt = d.t[hi] - d.t[lo];
      d.slip_h[i][k] = dt > 0.0 ? half_signed_square((d.wheel[i][hi] - d.wheel[i][lo]) / dt) : 0.0;
    }
  }

  ChannelSet& m = d.measured;
  const auto add = [&m](const std::string& name, const char* unit, Question q, ChannelKind kind,
                        std::vector<double> values) {
    m.info.push_back({name, unit, q, kind});
    m.values.push_back(std::move(values));
    return m.info.size() - 1;
  };
  d.dr_x = add("dead_reckoning.x_m", "m", Question::kSensorToPose, ChannelKind::kPosition, run.truth_x_m);
  d.dr_y = add("dead_reckoning.y_m", "m", Question::kSensorToPose, ChannelKind::kPosition, run.truth_y_m);
  d.dr_yaw = add("dead_reckoning.yaw_rad", "rad", Question::kSensorToPose, ChannelKind::kHeading,
                 run.truth_yaw_rad);
  d.sim_x = add("simulation.x_m", "m", Question::kCommandToPose, ChannelKind::kPosition, run.truth_x_m);
  d.sim_y = add("simulation.y_m", "m", Question::kCommandToPose, ChannelKind::kPosition, run.truth_y_m);
  d.sim_yaw = add("simulation.yaw_rad", "rad", Question::kCommandToPose, ChannelKind::kHeading,
                  run.truth_yaw_rad);
  for (std::size_t i = 0; i < d.modules; ++i) {
    const std::string name = d.swpc ? std::to_string(i + 1) : (i == 0 ? "l" : "r");
    d.sim_wheel.push_back(add("simulation.wheel_" + name + "_rad", "rad", Question::kCommandToSensor,
                              ChannelKind::kWheelAngle, run.wheel_rad[i]));
  }
  if (d.swpc) {
    for (std::size_t i = 0; i < d.modules; ++i) {
      d.sim_steer.push_back(add("simulation.steer_" + std::to_string(i + 1) + "_rad", "rad",
                                Question::kCommandToSensor, ChannelKind::kSteerAngle,
                                run.steer_rad[i]));
    }
  }
  // The first gyro reading covers no interval of the replay.
  std::vector<double> gyro = run.gyro_radps;
  gyro[0] = kNaN;
  d.sim_gyro = add("simulation.gyro_radps", "rad/s", Question::kCommandToSensor, ChannelKind::kYawRate,
                   gyro);
}

Replay::~Replay() = default;

const ChannelSet& Replay::measured() const { return impl_->measured; }

void Replay::predict(const RobotModel& model, ChannelSet& out, std::size_t end) const {
  const Impl& d = *impl_;
  if (out.info.size() != d.measured.info.size()) {
    out.info = d.measured.info;
    out.values.assign(d.measured.info.size(), std::vector<double>(d.n, kNaN));
  }
  const sim::PlantParams plant = sim::resolve_plant(model);
  end = std::min(end, d.n);
  d.dead_reckon(plant, out, end);
  d.resimulate(model, plant, out, end);
}

void Replay::Impl::dead_reckon(const sim::PlantParams& plant, ChannelSet& out,
                               std::size_t end) const {
  localization::EgConfig config;
  config.heading_source = localization::HeadingSource::kGyro;
  config.gyro_scale = plant.sensors.gyro.scale;
  config.gyro_bias_radps = plant.sensors.gyro.bias_rad_s;
  localization::EgOdometry eg(config);
  eg.reset(start);
  dr_px.resize(n);
  dr_py.resize(n);
  dr_pyaw.resize(n);
  dr_px[0] = start.x_m;
  dr_py[0] = start.y_m;
  dr_pyaw[0] = start.yaw_rad;
  const double g = plant.slip_gain_per_radps2;
  std::array<double, kMaxModules> dpsi{};
  std::array<double, kMaxModules> phi{};
  std::array<double, kMaxModules> steer_rate{};
  std::array<double, kMaxModules> wheel_rate{};
  // Integrate past `end` by the sensor delay so that the shifted pose exists up to `end`.
  const double horizon_s = t[end - 1] + plant.sensor_delay_s;
  std::size_t dr_end = end;
  while (dr_end < n && t[dr_end - 1] <= horizon_s) ++dr_end;
  for (std::size_t k = 1; k < dr_end; ++k) {
    const double dt = t[k] - t[k - 1];
    for (std::size_t i = 0; i < modules; ++i) {
      // The contact point rolls less than the wheel turns while it speeds up.
      dpsi[i] = wheel[i][k] - wheel[i][k - 1] - g * (slip_h[i][k] - slip_h[i][k - 1]);
    }
    Pose2 delta;
    if (!swpc) {
      delta = differential::forward_increment(plant.differential, dpsi[0], dpsi[1]);
    } else {
      for (std::size_t i = 0; i < modules; ++i) {
        const double dphi = steer[i][k] - steer[i][k - 1];
        phi[i] = steer[i][k - 1] + 0.5 * dphi + plant.modules[i].steering_offset_rad;
        steer_rate[i] = dphi / dt;
        wheel_rate[i] = dpsi[i] / dt;
      }
      const swpc::ForwardResult fit = swpc::forward(
          std::span<const SwpcModuleParams>(plant.modules.data(), modules),
          std::span<const double>(phi.data(), modules), std::span<const double>(steer_rate.data(), modules),
          std::span<const double>(wheel_rate.data(), modules));
      delta = fit.ok ? swpc::integrate_twist(fit.twist, dt) : Pose2{kNaN, kNaN, kNaN};
    }
    // gyro[k] is the mean rate over (t[k-1], t[k]].
    if (!eg.step(delta, dt, gyro[k], true)) {
      std::fill(dr_px.begin() + static_cast<std::ptrdiff_t>(k), dr_px.end(), kNaN);
      std::fill(dr_py.begin() + static_cast<std::ptrdiff_t>(k), dr_py.end(), kNaN);
      std::fill(dr_pyaw.begin() + static_cast<std::ptrdiff_t>(k), dr_pyaw.end(), kNaN);
      break;
    }
    const Pose2 p = eg.pose();
    dr_px[k] = p.x_m;
    dr_py[k] = p.y_m;
    dr_pyaw[k] = eg.unwrapped_yaw_rad();
  }
  // Encoders and gyro lag motion capture by the delay: the pose they give at t + delay is
  // where the robot was at t.
  const double delay = plant.sensor_delay_s;
  auto& ox = out.values[dr_x];
  auto& oy = out.values[dr_y];
  auto& oyaw = out.values[dr_yaw];
  std::size_t j = 0;
  for (std::size_t k = 0; k < end; ++k) {
    const double tq = t[k] + delay;
    while (j + 1 < dr_end && t[j + 1] <= tq) ++j;
    if (j + 1 >= dr_end) {
      ox[k] = dr_px[dr_end - 1];
      oy[k] = dr_py[dr_end - 1];
      oyaw[k] = dr_pyaw[dr_end - 1];
      continue;
    }
    const double f = std::clamp((tq - t[j]) / (t[j + 1] - t[j]), 0.0, 1.0);
    ox[k] = dr_px[j] + f * (dr_px[j + 1] - dr_px[j]);
    oy[k] = dr_py[j] + f * (dr_py[j + 1] - dr_py[j]);
    oyaw[k] = dr_pyaw[j] + f * (dr_pyaw[j + 1] - dr_pyaw[j]);
  }
}

void Replay::Impl::resimulate(const RobotModel& model, const sim::PlantParams& plant,
                              ChannelSet& out, std::size_t end) const {
  sim::SimOptions options;
  options.sensor_noise = false;
  options.quantize_encoders = false;
  options.motion_capture = false;
  options.start_pose = start;
  options.substep_s = swpc ? kSwpcSubstepS : kDifferentialSubstepS;
  if (swpc) {
    for (std::size_t i = 0; i < modules; ++i) {
      options.initial_steer_rad[i] = steer[i][0] + plant.modules[i].steering_offset_rad;
    }
  }
  sim::World world(model, options);
  const sim::OpenLoopController controller(nominal);
  HardwareState hw;
  world.read(hw);
  std::array<double, kMaxModules> wheel0{};
  for (std::size_t i = 0; i < modules; ++i) wheel0[i] = hw.wheel_angle_rad[i];
  const auto record = [&](std::size_t k) {
    const Pose2& p = world.true_pose();
    out.values[sim_x][k] = p.x_m;
    out.values[sim_y][k] = p.y_m;
    out.values[sim_yaw][k] = p.yaw_rad;
    for (std::size_t i = 0; i < modules; ++i) {
      out.values[sim_wheel[i]][k] = wheel[i][0] + hw.wheel_angle_rad[i] - wheel0[i];
      if (swpc) out.values[sim_steer[i]][k] = hw.steer_angle_rad[i];
    }
    out.values[sim_gyro][k] = k == 0 ? kNaN : hw.gyro_wz_radps;
  };
  record(0);
  ActuatorCommand command;
  for (std::size_t k = 1; k < end; ++k) {
    // The robot's controller (nominal model) steered from the steering angles it measured,
    // which the log holds: the replay gives the world the setpoints the robot got.
    HardwareState logged;
    logged.module_count = static_cast<std::uint32_t>(modules);
    for (std::size_t i = 0; i < modules; ++i) {
      logged.wheel_angle_rad[i] = wheel[i][k - 1];
      if (swpc) logged.steer_angle_rad[i] = steer[i][k - 1];
    }
    controller.velocity(cmd[k - 1], logged, command);
    if (world.step(t[k] - t[k - 1], command) != Status::kOk) {
      for (auto& v : out.values) std::fill(v.begin() + static_cast<std::ptrdiff_t>(k), v.end(), kNaN);
      return;
    }
    world.read(hw);
    record(k);
  }
}

std::vector<CandidateEffect> candidate_library(const RobotModel& nominal) {
  std::vector<CandidateEffect> out;
  for (const sim::EffectInfo& e : sim::effect_library(nominal)) {
    // An effect the nominal model already carries is refitted on top, not offered again.
    if (nominal.effects.count(e.name) != 0U) continue;
    CandidateEffect c;
    c.effect = e.name;
    for (const sim::EffectParamInfo& p : e.params) {
      ParamSpec s;
      s.name = p.key;
      s.scale = typical_magnitude(e.name);
      // A lag or delay is flat in its parameter near zero (shorter than an integration
      // step): start such fits inside the range, at a typical value.
      s.initial = p.identity <= p.min ? p.identity + s.scale : p.identity;
      s.lower = p.min;
      s.upper = p.max;
      c.params.push_back(s);
      c.identity.push_back(p.identity);
    }
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace swivel::model_gap
