// SPDX-License-Identifier: Apache-2.0
#include "docent_experiment.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include "swivel/differential/differential_kinematics.hpp"
#include "swivel/localization/eg_odometry.hpp"
#include "swivel/localization/lcakf.hpp"
#include "swivel/localization/lcalsm.hpp"
#include "swivel/localization/pose_ekf.hpp"
#include "swivel/sim/open_loop.hpp"
#include "swivel/sim/world.hpp"

namespace swivel::lab {
namespace {

using localization::EgOdometry;
using localization::Lcakf;
using localization::Lcalsm;
using localization::PoseEkf;

constexpr double kMaxRunS = 300.0;
// The kalman plugin's default initial gyro-bias uncertainty (KalmanConfig).
constexpr double kEkfInitialBiasSigmaRadps = 0.02;

std::size_t index(DocentMethod m) { return static_cast<std::size_t>(m); }

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27U)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31U);
}

double distance_m(const Pose2& a, const Pose2& b) {
  return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m);
}

// Every method as its plugin runs it: the kalman and lsm plugins each integrate their own
// E/G from the readings, so each gets its own EgOdometry configured the same way.
class Estimators {
 public:
  Estimators(const RobotModel& nominal, const Pose2& start) {
    localization::EgConfig eg;
    eg.heading_source = localization::HeadingSource::kGyro;
    eg.gyro_scale = nominal.sensors.gyro.scale;
    eg.gyro_bias_radps = nominal.sensors.gyro.bias_rad_s;
    for (EgOdometry& e : eg_) {
      e.set_config(eg);
      e.reset(start);
    }
    gyro_scale_ = eg.gyro_scale;
    gyro_bias_radps_ = eg.gyro_bias_radps;

    lcakf_.set_noise(localization::LcakfNoise{});
    lcakf_.reset(start.x_m, start.y_m, 0.0);

    localization::LsmConfig lsm;
    lsm.mode = localization::LsmMode::kPaper;
    paper_.configure(lsm);
    lsm.mode = localization::LsmMode::kHeadingAligned;
    heading_.configure(lsm);

    localization::EkfNoise noise;
    noise.gyro_noise_radps = nominal.sensors.gyro.noise_rad_s;
    ekf_.set_noise(noise);
    ekf_.reset(start, PoseEkf::Matrix3::Zero(), 0.0,
               kEkfInitialBiasSigmaRadps * kEkfInitialBiasSigmaRadps);
  }

  void step(const Pose2& delta, double dt_s, double gyro_radps, double stamp_s) {
    for (EgOdometry& e : eg_) {
      if (!e.step(delta, dt_s, gyro_radps, true)) throw std::runtime_error("E/G step rejected");
    }
    const Pose2 kf_in = eg_[index(DocentMethod::kLcakf)].pose();
    if (!lcakf_.step(dt_s, kf_in.x_m, kf_in.y_m)) throw std::runtime_error("LCAKF step rejected");
    push(paper_, eg_[index(DocentMethod::kLcalsmPaper)], stamp_s);
    push(heading_, eg_[index(DocentMethod::kLcalsmHeading)], stamp_s);
    const double corrected = (gyro_radps - gyro_bias_radps_) / gyro_scale_;
    if (ekf_.step(delta, dt_s, corrected, true) != localization::EkfResult::kOk) {
      throw std::runtime_error("EKF step rejected");
    }
  }

  [[nodiscard]] std::array<Pose2, kDocentMethodCount> estimates() const {
    std::array<Pose2, kDocentMethodCount> out{};
    out[index(DocentMethod::kEg)] = eg_[index(DocentMethod::kEg)].pose();
    const Pose2 kf_eg = eg_[index(DocentMethod::kLcakf)].pose();
    out[index(DocentMethod::kLcakf)] = Pose2{lcakf_.x_m(), lcakf_.y_m(), kf_eg.yaw_rad};
    out[index(DocentMethod::kLcalsmPaper)] =
        paper_.output(eg_[index(DocentMethod::kLcalsmPaper)].pose());
    out[index(DocentMethod::kLcalsmHeading)] =
        heading_.output(eg_[index(DocentMethod::kLcalsmHeading)].pose());
    out[index(DocentMethod::kEkf)] = ekf_.pose();
    return out;
  }

  /// Distance of method m's E/G input from the reference E/G (0 for the EKF, which has none).
  [[nodiscard]] double eg_mismatch_m(std::size_t m) const {
    if (m == index(DocentMethod::kEkf)) return 0.0;
    return distance_m(eg_[m].pose(), eg_[index(DocentMethod::kEg)].pose());
  }

  [[nodiscard]] double ekf_bias_radps() const { return ekf_.bias_radps(); }

 private:
  static void push(Lcalsm& lsm, const EgOdometry& eg, double stamp_s) {
    lsm.push(eg.pose(), eg.unwrapped_yaw_rad(), eg.distance_m(), stamp_s);
  }

  std::array<EgOdometry, kDocentMethodCount> eg_{};
  double gyro_scale_ = 1.0;
  double gyro_bias_radps_ = 0.0;
  Lcakf lcakf_;
  Lcalsm paper_;
  Lcalsm heading_;
  PoseEkf ekf_;
};

// The true robot of one run: the nominal model with the drawn errors as named effects.
RobotModel true_model(const RobotModel& nominal, const DocentRunDraw& draw,
                      const DocentErrorModel& errors) {
  RobotModel truth = nominal;
  truth.sensors.gyro.noise_rad_s = errors.gyro_noise_radps;
  truth.effects["gyro_bias"] = {{"bias_rad_s", draw.gyro_bias_radps}};
  truth.effects["gyro_scale"] = {{"scale", draw.gyro_scale}};
  truth.effects["wheel_radius"] = {{"left_scale", draw.wheel_radius_scale_left},
                                   {"right_scale", draw.wheel_radius_scale_right}};
  return truth;
}

void finish_stats(DocentRunResult& r) {
  for (std::size_t m = 0; m < kDocentMethodCount; ++m) {
    const std::vector<double>& e = r.errors_m[m];
    DocentMethodStats& s = r.stats[m];
    if (e.empty()) continue;
    double sum = 0.0;
    for (double v : e) {
      s.max_error_m = std::max(s.max_error_m, v);
      sum += v;
    }
    s.mean_error_m = sum / static_cast<double>(e.size());
    double var = 0.0;
    for (double v : e) var += (v - s.mean_error_m) * (v - s.mean_error_m);
    s.std_error_m = std::sqrt(var / static_cast<double>(e.size()));
  }
}

}  // namespace

const char* docent_method_label(DocentMethod m) {
  switch (m) {
    case DocentMethod::kEg: return "E/G";
    case DocentMethod::kLcakf: return "LCAKF";
    case DocentMethod::kLcalsmPaper: return "LCALSM";
    case DocentMethod::kLcalsmHeading: return "LCALSM-HA*";
    case DocentMethod::kEkf: return "EKF*";
  }
  return "?";
}

const char* docent_method_key(DocentMethod m) {
  switch (m) {
    case DocentMethod::kEg: return "eg";
    case DocentMethod::kLcakf: return "lcakf";
    case DocentMethod::kLcalsmPaper: return "lcalsm_paper";
    case DocentMethod::kLcalsmHeading: return "lcalsm_heading_aligned";
    case DocentMethod::kEkf: return "ekf";
  }
  return "?";
}

std::vector<DocentScenario> docent_scenarios() {
  return {DocentScenario{"S1", 0.0, 3.0, 8.0}, DocentScenario{"S2", 0.0, 6.0, 8.0}};
}

DocentRunDraw draw_docent_run(const DocentErrorModel& errors, std::uint64_t seed,
                              std::size_t scenario_index, std::size_t run) {
  DocentRunDraw d;
  d.seed = splitmix64(splitmix64(splitmix64(seed) + scenario_index) + run);
  std::mt19937_64 rng(d.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  d.gyro_bias_radps = errors.gyro_bias_sigma_radps * normal(rng);
  d.gyro_scale = 1.0 + errors.gyro_scale_sigma * normal(rng);
  d.wheel_radius_scale_left = 1.0 + errors.wheel_radius_error_max * uniform(rng);
  d.wheel_radius_scale_right = 1.0 + errors.wheel_radius_error_max * uniform(rng);
  return d;
}

DocentRunResult run_docent(const RobotModel& nominal, const DocentScenario& scenario,
                           const DocentRunDraw& draw, const DocentExperimentConfig& config,
                           bool keep_trace) {
  if (nominal.drivetrain != DrivetrainKind::kDifferential) {
    throw std::invalid_argument(nominal.source_file +
                                ": the docent experiment needs a "
                                "differential robot");
  }
  const DocentDriveProfile& drive = config.drive;
  const Pose2 start{scenario.start_x_m, scenario.line_y_m, 0.0};

  sim::SimOptions options;
  options.seed = draw.seed;
  options.sensor_noise = true;
  options.quantize_encoders = true;
  options.motion_capture = false;  // the corridor has none; nothing may use the truth
  options.nonsystematic.wheel_slip_std = config.errors.wheel_slip_std;
  options.nonsystematic.correlation_time_s = config.errors.slip_correlation_time_s;
  options.start_pose = start;
  sim::World world(true_model(nominal, draw, config.errors), options);
  const sim::OpenLoopController controller(nominal);
  Estimators estimators(nominal, start);

  DocentRunResult result;
  result.draw = draw;
  const double length_m = scenario.end_x_m - scenario.start_x_m;
  const auto sample_count =
      static_cast<std::size_t>(std::max(1.0, std::round(length_m / config.sample_spacing_m)));
  std::size_t next_sample = 1;
  const double dt_s = 1.0 / drive.rate_hz;
  const auto trace_every =
      static_cast<std::int64_t>(std::max(1.0, std::round(config.trace_period_s * drive.rate_hz)));

  HardwareState prev;
  HardwareState now;
  world.read(prev);
  ActuatorCommand command;
  const auto max_steps = static_cast<std::int64_t>(kMaxRunS * drive.rate_hz);
  for (std::int64_t k = 0;; ++k) {
    if (k > max_steps) {
      throw std::runtime_error(scenario.name +
                               ": the robot did not reach x = " + std::to_string(scenario.end_x_m) +
                               " m within " + std::to_string(kMaxRunS) + " s");
    }
    const double t_s = static_cast<double>(k) * dt_s;
    const Pose2& truth = world.true_pose();
    // A line follower on the true pose keeps the robot on the corridor line, so that the
    // truth is the straight run the paper evaluates and every error is the estimator's.
    Twist2 twist;
    if (t_s >= drive.still_before_s) {
      const double remaining_m = std::max(0.0, scenario.end_x_m - truth.x_m);
      double v = std::min({drive.cruise_speed_mps, drive.accel_mps2 * (t_s - drive.still_before_s),
                           std::sqrt(2.0 * drive.accel_mps2 * remaining_m)});
      v = std::max(v, drive.min_speed_mps);
      const double lateral_m = truth.y_m - scenario.line_y_m;
      twist.vx_mps = v;
      twist.wz_radps =
          -(drive.lateral_gain_per_m2 * v * lateral_m +
            drive.yaw_gain_per_s * std::remainder(truth.yaw_rad, 2.0 * std::numbers::pi));
    }
    controller.velocity(twist, prev, command);
    if (world.step(dt_s, command) != Status::kOk) {
      throw std::runtime_error(std::string("simulation failed: ") + world.last_error());
    }
    world.read(now);
    const Pose2 delta = differential::forward_increment(
        nominal.differential, now.wheel_angle_rad[0] - prev.wheel_angle_rad[0],
        now.wheel_angle_rad[1] - prev.wheel_angle_rad[1]);
    estimators.step(delta, dt_s, now.gyro_wz_radps, world.time_s());
    prev = now;

    const Pose2& moved = world.true_pose();
    const std::array<Pose2, kDocentMethodCount> est = estimators.estimates();
    for (std::size_t m = 0; m < kDocentMethodCount; ++m) {
      result.stats[m].eg_input_mismatch_m =
          std::max(result.stats[m].eg_input_mismatch_m, estimators.eg_mismatch_m(m));
    }
    if (keep_trace && (k % trace_every == 0)) {
      result.trace.push_back(DocentTracePoint{world.time_s(), moved, est});
    }
    const double target_x_m = scenario.start_x_m + length_m * static_cast<double>(next_sample) /
                                                       static_cast<double>(sample_count);
    if (moved.x_m >= target_x_m) {
      result.sample_x_m.push_back(moved.x_m);
      for (std::size_t m = 0; m < kDocentMethodCount; ++m) {
        result.errors_m[m].push_back(distance_m(est[m], moved));
      }
      ++next_sample;
      if (next_sample > sample_count) {
        if (keep_trace) result.trace.push_back(DocentTracePoint{world.time_s(), moved, est});
        break;
      }
    }
  }
  result.duration_s = world.time_s();
  result.true_end = world.true_pose();
  result.ekf_bias_radps = estimators.ekf_bias_radps();
  finish_stats(result);
  return result;
}

std::vector<DocentScenarioResult> run_docent_experiment(const RobotModel& nominal,
                                                        const DocentExperimentConfig& config) {
  std::vector<DocentScenarioResult> out;
  const std::vector<DocentScenario> scenarios = docent_scenarios();
  for (std::size_t s = 0; s < scenarios.size(); ++s) {
    DocentScenarioResult sr;
    sr.scenario = scenarios[s];
    for (std::size_t r = 0; r < config.runs; ++r) {
      const DocentRunDraw draw = draw_docent_run(config.errors, config.seed, s, r);
      sr.runs.push_back(
          run_docent(nominal, scenarios[s], draw, config, config.keep_trace && r == 0));
    }
    out.push_back(std::move(sr));
  }
  return out;
}

}  // namespace swivel::lab
