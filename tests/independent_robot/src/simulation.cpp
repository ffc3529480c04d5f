// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "angles.hpp"
#include "controller.hpp"
#include "plant.hpp"
#include "random_stream.hpp"
#include "swivel/independent/nominal_robots.hpp"
#include "swivel/independent/tour.hpp"

namespace swivel::independent {
namespace {

constexpr double kControlPeriodS = 0.001;
// A wheel turning slower than this does not lose counts (nothing passes the read head).
constexpr double kDropMinWheelRateRadps = 0.5;

// A moment at which the integration stops to take a sample.
struct Event {
  double t_s = 0.0;
  std::size_t row = 0;
  bool truth = false;   // the row's own time: pose for motion capture
  bool sensor = false;  // the row's time minus the sensor delay: encoders and gyro
};

// What the encoders and the gyro's integrator hold at a sensor event.
struct SensorSample {
  double yaw_rad = 0.0;
  std::array<double, kMaxWheels> wheel_rad{};
  std::array<double, kMaxWheels> steer_rad{};
};

class Simulation {
 public:
  explicit Simulation(const RunSpec& spec)
      : spec_(spec),
        wheels_(wheel_count(spec.robot)),
        tour_(spec.tour.empty() ? make_tour(spec.robot, spec.steering, spec.seed, spec.duration_s)
                                : spec.tour),
        process_(spec.seed, kProcessStream),
        sensor_(spec.seed, kSensorStream),
        clock_(spec.seed, kClockStream),
        plant_(true_plant(
            spec, RandomStream(spec.seed, kOutsideStream).uniform(0.0, 2.0 * std::numbers::pi))),
        controller_(spec) {
    RandomStream start(spec.seed, kStartStream);
    start_ = spec.start_pose ? *spec.start_pose
                             : Pose{start.uniform(-0.5, 0.5), start.uniform(-0.5, 0.5),
                                    start.uniform(-std::numbers::pi, std::numbers::pi)};
  }

  RunRecord run() {
    make_row_times();
    mark_motion_capture_frames();
    make_events();
    integrate();
    return assemble();
  }

 private:
  void make_row_times() {
    const NoiseSpec& n = spec_.noise;
    const auto count = static_cast<std::size_t>(std::llround(spec_.duration_s * n.row_rate_hz));
    rows_.assign(count, RunRow{});
    for (std::size_t k = 0; k < count; ++k) {
      const double jitter =
          std::clamp(n.row_jitter_s * clock_.gaussian(), -n.row_jitter_clip_s, n.row_jitter_clip_s);
      rows_[k].t_s = k == 0 ? 0.0 : static_cast<double>(k) / n.row_rate_hz + jitter;
      rows_[k].cmd = setpoint_at(tour_, rows_[k].t_s);
    }
  }

  // Motion capture runs on its own clock; a row carries a pose when a frame fell in
  // (previous row's time, its time].
  void mark_motion_capture_frames() {
    const NoiseSpec& n = spec_.noise;
    const double period = 1.0 / (n.mocap_rate_hz * (1.0 + 1e-6 * n.mocap_clock_ppm));
    const double last = rows_.back().t_s;
    auto row = rows_.begin();
    // The capture clock adds its period frame by frame, as a real one does; the runs this
    // wrote are recorded, so the sum stays.
    // NOLINTNEXTLINE(clang-analyzer-security.FloatLoopCounter,cert-flp30-c)
    for (double f = clock_.uniform(0.0, period); f <= last; f += period) {
      const bool lost = clock_.chance(n.mocap_dropout);
      row = std::lower_bound(row, rows_.end(), f,
                             [](const RunRow& r, double t) { return r.t_s < t; });
      if (!lost) row->has_truth = true;
    }
  }

  void make_events() {
    const double delay = spec_.truth.sensor_delay_s;
    events_.reserve(2 * rows_.size());
    for (std::size_t k = 0; k < rows_.size(); ++k) {
      if (delay == 0.0) {
        events_.push_back(Event{rows_[k].t_s, k, true, true});
      } else {
        events_.push_back(Event{rows_[k].t_s, k, true, false});
        events_.push_back(Event{rows_[k].t_s - delay, k, false, true});
      }
    }
    std::stable_sort(events_.begin(), events_.end(),
                     [](const Event& a, const Event& b) { return a.t_s < b.t_s; });
    sensors_.assign(rows_.size(), SensorSample{});
  }

  // The steering angles the encoders report at control tick `tick` (delayed like every
  // encoder reading), as the controller reads them.
  [[nodiscard]] std::array<double, kMaxWheels> measured_steering_at_tick(std::size_t tick) const {
    const double back = static_cast<double>(tick) - spec_.truth.sensor_delay_s / kControlPeriodS;
    std::array<double, kMaxWheels> phi = steer_by_tick_.front();
    if (back > 0.0) {
      const auto i = static_cast<std::size_t>(std::floor(back));
      const double f = back - static_cast<double>(i);
      phi = steer_by_tick_[i];
      if (i + 1 < steer_by_tick_.size()) {
        for (std::size_t m = 0; m < wheels_; ++m) {
          phi[m] += f * (steer_by_tick_[i + 1][m] - phi[m]);
        }
      }
    }
    return measured_steering(phi);
  }

  [[nodiscard]] std::array<double, kMaxWheels> measured_steering(
      const std::array<double, kMaxWheels>& phi) const {
    std::array<double, kMaxWheels> out{};
    if (spec_.robot == Robot::kDocent) return out;
    for (std::size_t m = 0; m < wheels_; ++m) {
      out[m] =
          quantize(phi[m] - plant_.params().modules[m].steering_offset_rad, kEncoderCountsPerRev);
    }
    return out;
  }

  void integrate() {
    const NoiseSpec& n = spec_.noise;
    PlantState x;
    x.pose = start_;
    steer_by_tick_.push_back(x.steer_rad);

    // Random-walk slip: an Ornstein-Uhlenbeck process per wheel, exact over one period,
    // started in its stationary distribution.
    const double keep = std::exp(-kControlPeriodS / n.slip_correlation_s);
    const double kick = n.slip_std * std::sqrt(1.0 - keep * keep);
    std::array<double, kMaxWheels> slip{};
    for (std::size_t i = 0; i < wheels_; ++i) slip[i] = n.slip_std * process_.gaussian();

    const OutsideEffects& o = spec_.outside;
    double next_drop_s = o.dropped_counts_interval_s > 0.0
                             ? process_.exponential(o.dropped_counts_interval_s)
                             : HUGE_VAL;
    std::size_t drop_wheel = 0;
    bool drop_pending = false;

    const bool ideal_wheels = plant_.params().wheel_time_constant_s <= 0.0;
    const bool ideal_steering = plant_.params().steer_time_constant_s <= 0.0;
    std::array<double, kMaxWheels> previous_wheel_sp{};
    std::size_t e = 0;
    DriveInputs inputs;
    while (e < events_.size() && events_[e].t_s <= 0.0) record(events_[e++], x, inputs);

    const double last = rows_.back().t_s;
    const auto ticks = static_cast<std::size_t>(std::ceil(last / kControlPeriodS)) + 1;
    for (std::size_t k = 0; k < ticks; ++k) {
      const double t = static_cast<double>(k) * kControlPeriodS;
      const double t_next = static_cast<double>(k + 1) * kControlPeriodS;
      const DriveSetpoints sp =
          controller_.update(setpoint_at(tour_, t), measured_steering_at_tick(k), kControlPeriodS);
      for (std::size_t i = 0; i < wheels_; ++i) {
        inputs.wheel_rate_sp[i] = sp.wheel_radps[i];
        inputs.wheel_accel[i] = (sp.wheel_radps[i] - previous_wheel_sp[i]) / kControlPeriodS;
        inputs.steer_rate_sp[i] = sp.steer_radps[i];
        inputs.slip[i] = slip[i];
        slip[i] = keep * slip[i] + kick * process_.gaussian();
        if (ideal_wheels) x.wheel_rate_radps[i] = sp.wheel_radps[i];
        if (ideal_steering) x.steer_rate_radps[i] = sp.steer_radps[i];
      }
      previous_wheel_sp = sp.wheel_radps;
      inputs.commanded = controller_.limited();

      if (t >= next_drop_s && !drop_pending) {
        drop_pending = true;
        drop_wheel = static_cast<std::size_t>(process_.integer(0, static_cast<int>(wheels_) - 1));
      }
      if (drop_pending && std::abs(sp.wheel_radps[drop_wheel]) > kDropMinWheelRateRadps) {
        // Missed edges leave the count behind the motion.
        const int counts = process_.integer(o.dropped_counts_min, o.dropped_counts_max);
        lost_counts_[drop_wheel] += sp.wheel_radps[drop_wheel] > 0.0 ? -counts : counts;
        drop_pending = false;
        next_drop_s = t + process_.exponential(o.dropped_counts_interval_s);
      }

      double tc = t;
      while (e < events_.size() && events_[e].t_s <= t_next) {
        if (events_[e].t_s > tc) {
          plant_.advance(x, inputs, events_[e].t_s - tc);
          tc = events_[e].t_s;
        }
        record(events_[e++], x, inputs);
      }
      if (t_next > tc) plant_.advance(x, inputs, t_next - tc);
      steer_by_tick_.push_back(x.steer_rad);
    }
  }

  void record(const Event& ev, const PlantState& x, const DriveInputs& inputs) {
    if (ev.truth) {
      Twist twist;
      (void)plant_.rate(x, inputs, twist);
      rows_[ev.row].true_pose = x.pose;
      rows_[ev.row].true_twist = twist;
    }
    if (ev.sensor) {
      SensorSample& s = sensors_[ev.row];
      s.yaw_rad = x.pose.yaw_rad;
      const double count = 2.0 * std::numbers::pi / kEncoderCountsPerRev;
      for (std::size_t i = 0; i < wheels_; ++i) {
        s.wheel_rad[i] = quantize(x.wheel_rad[i], kEncoderCountsPerRev) +
                         static_cast<double>(lost_counts_[i]) * count;
      }
      s.steer_rad = measured_steering(x.steer_rad);
    }
  }

  RunRecord assemble() {
    const NoiseSpec& n = spec_.noise;
    const TrueEffects& t = spec_.truth;
    const OutsideEffects& o = spec_.outside;
    double previous_yaw = start_.yaw_rad;
    double previous_t = -1.0 / n.row_rate_hz;
    for (std::size_t k = 0; k < rows_.size(); ++k) {
      RunRow& row = rows_[k];
      const SensorSample& s = sensors_[k];
      row.wheel_rad = s.wheel_rad;
      row.steer_rad = s.steer_rad;
      // The gyro reports the mean yaw rate since the previous row (of the delayed state).
      const double mean_rate = (s.yaw_rad - previous_yaw) / (row.t_s - previous_t);
      const double drift = o.gyro_drift_rad_s * (2.0 * row.t_s / spec_.duration_s - 1.0);
      row.gyro_wz_radps = t.gyro_scale * mean_rate + t.gyro_bias_rad_s + drift +
                          n.gyro_noise_rad_s * sensor_.gaussian();
      previous_yaw = s.yaw_rad;
      previous_t = row.t_s;
      if (row.has_truth) {
        row.truth.x_m = row.true_pose.x_m + o.floor_drift_x_mps * row.t_s +
                        n.mocap_position_noise_m * sensor_.gaussian();
        row.truth.y_m = row.true_pose.y_m + o.floor_drift_y_mps * row.t_s +
                        n.mocap_position_noise_m * sensor_.gaussian();
        row.truth.yaw_rad =
            wrap_angle(row.true_pose.yaw_rad + n.mocap_yaw_noise_rad * sensor_.gaussian());
      }
    }
    RunRecord record;
    record.robot = spec_.robot;
    record.rows = std::move(rows_);
    return record;
  }

  const RunSpec& spec_;
  std::size_t wheels_;
  std::vector<TourSegment> tour_;
  RandomStream process_;
  RandomStream sensor_;
  RandomStream clock_;
  Plant plant_;
  Controller controller_;
  Pose start_;
  std::vector<RunRow> rows_;
  std::vector<Event> events_;
  std::vector<SensorSample> sensors_;
  std::vector<std::array<double, kMaxWheels>> steer_by_tick_;
  std::array<std::int64_t, kMaxWheels> lost_counts_{};
};

}  // namespace

RunRecord simulate(const RunSpec& spec) {
  validate(spec);
  return Simulation(spec).run();
}

}  // namespace swivel::independent
