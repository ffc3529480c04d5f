// SPDX-License-Identifier: Apache-2.0
// Each effect the generator can give the true robot, in a situation where its size can be
// read off directly; the library's names and messages; what a correct workflow should name.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <stdexcept>
#include <string>

#include "run_fixtures.hpp"
#include "swivel/independent/library_effects.hpp"
#include "swivel/independent/outside_effects.hpp"
#include "swivel/independent/simulation.hpp"

namespace swivel::independent {
namespace {

using test::count_rad;
using test::quiet_run;
using test::row_at;
using test::rows_between;
using test::step_tour;
using test::wheel_at;

TEST(Effects, GyroScaleAndBiasShowInTheGyroReading) {
  RunSpec spec = quiet_run(Robot::kDocent, 8.0, step_tour(2.0, Twist{0.0, 0.0, 0.6}));
  set_true_effect(spec, "gyro_scale.scale=1.02");
  set_true_effect(spec, "gyro_bias.bias_rad_s=0.003");
  const RunRecord run = simulate(spec);
  EXPECT_NEAR(row_at(run, 1.0).gyro_wz_radps, 0.003, 1e-12);
  for (const RunRow* r : rows_between(run, 3.0, 7.9)) {
    EXPECT_NEAR(r->gyro_wz_radps, 1.02 * 0.6 + 0.003, 1e-9);
  }
}

TEST(Effects, WheelRadiusChangesTheMotionNotTheEncoders) {
  RunSpec spec = quiet_run(Robot::kDocent, 8.0, step_tour(2.0, Twist{0.3, 0.0, 0.0}));
  set_true_effect(spec, "wheel_radius.left_scale=1.02");
  const RunRecord run = simulate(spec);
  const auto rows = rows_between(run, 3.0, 7.9);
  const RunRow& a = *rows.front();
  const RunRow& b = *rows.back();
  const double dt = b.t_s - a.t_s;
  // The encoders turn as the controller asks, v / r_nominal.
  EXPECT_NEAR(b.wheel_rad[0] - a.wheel_rad[0], 0.3 / 0.075 * dt, count_rad());
  // The larger left wheel covers 2 % more ground: v = 1.01 x 0.3, turning right at
  // -0.02 x 0.3 / 0.4 rad/s.
  EXPECT_NEAR(b.true_twist.vx_mps, 1.01 * 0.3, 1e-9);
  EXPECT_NEAR(b.gyro_wz_radps, -0.02 * 0.3 / 0.40, 1e-9);
}

TEST(Effects, TrackWidthSlowsTheTurnByItsScale) {
  RunSpec spec = quiet_run(Robot::kDocent, 8.0, step_tour(2.0, Twist{0.0, 0.0, 0.6}));
  set_true_effect(spec, "track_width.scale=1.04");
  const RunRecord run = simulate(spec);
  for (const RunRow* r : rows_between(run, 3.0, 7.9)) {
    EXPECT_NEAR(r->gyro_wz_radps, 0.6 / 1.04, 1e-9);
  }
}

// The controller aligns the measured angle with the motion, so the true casters stand off by
// the steering offset and the robot travels that much further counter-clockwise.
TEST(Effects, SteeringOffsetTurnsTheDirectionOfTravel) {
  RunSpec spec = quiet_run(Robot::kSwpc4, 8.0, step_tour(1.5, Twist{0.0, 0.2, 0.0}));
  for (int i = 1; i <= 4; ++i) {
    set_true_effect(spec, "steering_offset.module_" + std::to_string(i) + "_rad=0.02");
  }
  const RunRecord run = simulate(spec);
  const auto rows = rows_between(run, 5.0, 7.99);
  for (const RunRow* r : rows) {
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_NEAR(r->steer_rad[i], std::numbers::pi / 2, 2.0 * count_rad());
    }
  }
  const RunRow& a = *rows.front();
  const RunRow& b = *rows.back();
  const double direction = std::atan2(b.truth.y_m - a.truth.y_m, b.truth.x_m - a.truth.x_m);
  EXPECT_NEAR(direction, std::numbers::pi / 2 + 0.02, 1.5e-3);
}

// Encoders of a delayed robot read what the undelayed one read delay_s earlier, while motion
// capture is the same; fitted against motion capture, the encoders lag by delay_s.
TEST(Effects, SensorLatencyDelaysEncodersAndGyroAgainstMotionCapture) {
  const std::vector<TourSegment> tour{
      TourSegment{0.0, 0.0, Twist{}},         TourSegment{2.0, 0.0, {0.3, 0.0, 0.0}},
      TourSegment{4.0, 1.0, {0.1, 0.0, 0.0}}, TourSegment{6.0, 0.0, {0.0, 0.0, 0.0}},
      TourSegment{7.0, 0.0, {0.0, 0.0, 0.5}}, TourSegment{9.0, 0.0, {0.0, 0.0, 0.0}}};
  const RunSpec prompt = quiet_run(Robot::kDocent, 10.0, tour);
  RunSpec late = prompt;
  set_true_effect(late, "sensor_latency.delay_s=0.06");
  const RunRecord a = simulate(prompt);
  const RunRecord b = simulate(late);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  for (std::size_t k = 0; k < a.rows.size(); ++k) {
    // The same motion (the integration only stops at other times in between).
    ASSERT_NEAR(a.rows[k].truth.x_m, b.rows[k].truth.x_m, 1e-12);
    ASSERT_NEAR(a.rows[k].truth.yaw_rad, b.rows[k].truth.yaw_rad, 1e-12);
    const double t = b.rows[k].t_s;
    EXPECT_NEAR(b.rows[k].wheel_rad[1], wheel_at(a, 1, t - 0.06), 1.5 * count_rad()) << "t " << t;
  }
  // The shift that best lines up encoder distance r psi_R with motion capture's x.
  const auto best_shift = [](const RunRecord& run) {
    double best = 0.0;
    double best_error = HUGE_VAL;
    for (int ms = -20; ms <= 100; ++ms) {
      const double shift = 1e-3 * ms;
      double error = 0.0;
      for (const RunRow* r : rows_between(run, 1.5, 6.5)) {
        const double d = 0.075 * wheel_at(run, 1, r->t_s + shift) - r->truth.x_m;
        error += d * d;
      }
      if (error < best_error) {
        best_error = error;
        best = shift;
      }
    }
    return best;
  };
  EXPECT_NEAR(best_shift(a), 0.0, 2e-3);
  EXPECT_NEAR(best_shift(b), 0.06, 2e-3);
  // The gyro's first reading of the turn comes delay_s later.
  const auto turn_onset = [](const RunRecord& run) {
    for (const RunRow& r : run.rows) {
      if (r.t_s > 6.5 && r.gyro_wz_radps > 0.01) return r.t_s;
    }
    return HUGE_VAL;
  };
  EXPECT_NEAR(turn_onset(b) - turn_onset(a), 0.06, 0.011);
}

TEST(Effects, ActuatorLagMakesWheelsFollowAFirstOrderStep) {
  RunSpec spec = quiet_run(Robot::kDocent, 4.0, step_tour(2.0, Twist{0.3, 0.0, 0.0}));
  spec.truth.linear_accel_limit_mps2 = 1000.0;  // a true step: 4 rad/s from the tick at 2 s
  set_true_effect(spec, "actuator_lag.time_constant_s=0.08");
  const RunRecord run = simulate(spec);
  for (const RunRow* r : rows_between(run, 2.0, 3.99)) {
    const double s = r->t_s - 2.0;
    const double expected = 4.0 * (s - 0.08 * (1.0 - std::exp(-s / 0.08)));
    EXPECT_NEAR(r->wheel_rad[0], expected, count_rad()) << "t " << r->t_s;
  }
}

// A turn in place from casters at 0 asks module 1 for more than 6 rad/s of steering until it
// is 1.5 rad round: the drive gets a constant 6 rad/s setpoint, which a lag of tau follows
// as 6 (s - tau (1 - exp(-s / tau))).
TEST(Effects, SteeringLagSlowsTheCastersButNotTheWheels) {
  for (const double tau : {0.0, 0.08}) {
    RunSpec spec = quiet_run(Robot::kSwpc4, 3.0, step_tour(2.0, Twist{0.0, 0.0, 1.0}));
    spec.truth.angular_accel_limit_radps2 = 1000.0;  // a true step in yaw rate
    spec.truth.steering_time_constant_s = tau;
    const RunRecord run = simulate(spec);
    for (const RunRow* r : rows_between(run, 2.0, 3.0)) {
      if (r->steer_rad[0] > 1.3) break;
      const double s = r->t_s - 2.0;
      const double expected = 6.0 * (s - tau * (1.0 - std::exp(-s / std::max(tau, 1e-9))));
      EXPECT_NEAR(r->steer_rad[0], expected, count_rad()) << "tau " << tau << " t " << r->t_s;
    }
  }

  // Straight ahead the casters need no steering: the wheels follow the step as without lag.
  RunSpec straight = quiet_run(Robot::kSwpc4, 4.0, step_tour(2.0, Twist{0.22, 0.0, 0.0}));
  straight.truth.linear_accel_limit_mps2 = 1000.0;
  set_true_effect(straight, "steering_lag.time_constant_s=0.08");
  const RunRecord run = simulate(straight);
  for (const RunRow* r : rows_between(run, 2.0, 3.99)) {
    EXPECT_NEAR(r->wheel_rad[2], 4.0 * (r->t_s - 2.0), count_rad()) << "t " << r->t_s;
  }
}

// Acceleration slip loses g v^2 / (2 r) of ground while speeding up to v and wins it back
// while stopping.
TEST(Effects, SlipGainLosesGroundWhileSpeedingUpAndWinsItBackWhileStopping) {
  RunSpec spec = quiet_run(Robot::kDocent, 10.0,
                           {TourSegment{0.0, 0.0, Twist{}}, TourSegment{2.0, 0.0, {0.3, 0.0, 0.0}},
                            TourSegment{6.0, 0.0, {0.0, 0.0, 0.0}}});
  set_true_effect(spec, "slip.gain_per_radps2=0.003");
  const RunRecord run = simulate(spec);
  const auto deficit = [&](double t) {
    const RunRow& r = row_at(run, t);
    return 0.075 * r.wheel_rad[0] - r.truth.x_m;
  };
  const double tolerance = 0.075 * count_rad();
  EXPECT_NEAR(deficit(4.0), 0.003 * 0.3 * 0.3 / (2.0 * 0.075), tolerance);
  EXPECT_NEAR(deficit(9.0), 0.0, tolerance);
}

TEST(Outside, FloorDriftMovesMotionCaptureOnly) {
  RunSpec spec = quiet_run(Robot::kDocent, 20.0, {TourSegment{0.0, 0.0, Twist{}}});
  set_outside_effect(spec, "floor_drift.vx_mps=0.002");
  set_outside_effect(spec, "floor_drift.vy_mps=-0.001");
  for (const RunRow& r : simulate(spec).rows) {
    if (!r.has_truth) continue;
    EXPECT_NEAR(r.truth.x_m, 0.002 * r.t_s, 1e-12);
    EXPECT_NEAR(r.truth.y_m, -0.001 * r.t_s, 1e-12);
    EXPECT_EQ(r.wheel_rad[0], 0.0);
    EXPECT_EQ(r.gyro_wz_radps, 0.0);
  }
}

TEST(Outside, DroppedCountsComeInBurstsOfFiveToFifty) {
  const RunSpec clean = quiet_run(Robot::kDocent, 60.0, step_tour(1.5, Twist{0.3, 0.0, 0.0}));
  RunSpec dropping = clean;
  set_outside_effect(dropping, "dropped_counts.interval_s=4");
  const RunRecord a = simulate(clean);
  const RunRecord b = simulate(dropping);
  int bursts = 0;
  std::array<long, 2> lost_before{0, 0};
  for (std::size_t k = 0; k < a.rows.size(); ++k) {
    ASSERT_EQ(a.rows[k].truth.x_m, b.rows[k].truth.x_m);
    for (std::size_t w = 0; w < 2; ++w) {
      const long lost =
          std::lround((a.rows[k].wheel_rad[w] - b.rows[k].wheel_rad[w]) / count_rad());
      if (lost != lost_before[w]) {
        ++bursts;
        EXPECT_GE(lost - lost_before[w], 5);
        EXPECT_LE(lost - lost_before[w], 50);
        lost_before[w] = lost;
      }
    }
  }
  EXPECT_GE(bursts, 6);  // about 15 expected in 58 s of driving
  EXPECT_LE(bursts, 30);
}

TEST(Outside, EccentricWheelWobblesTheYawRateOncePerTurn) {
  RunSpec spec = quiet_run(Robot::kDocent, 12.0, step_tour(1.5, Twist{0.3, 0.0, 0.0}));
  set_outside_effect(spec, "eccentric_wheel.wheel=2");
  set_outside_effect(spec, "eccentric_wheel.amplitude=0.015");
  const RunRecord run = simulate(spec);
  // Right wheel's ground speed r (1 + a cos psi) psi_dot: yaw rate r a psi_dot cos(psi) / b.
  const double amplitude = 0.075 * 0.015 * 4.0 / 0.40;
  double peak = 0.0;
  double sum = 0.0;
  const double period = 2.0 * std::numbers::pi / 4.0;
  const auto rows = rows_between(run, 3.0, 3.0 + 5.0 * period);  // five whole turns
  for (const RunRow* r : rows) {
    peak = std::max(peak, std::abs(r->gyro_wz_radps));
    sum += r->gyro_wz_radps;
  }
  EXPECT_NEAR(peak, amplitude, 0.03 * amplitude);
  EXPECT_NEAR(sum / static_cast<double>(rows.size()), 0.0, 0.05 * amplitude);
}

TEST(Outside, GyroDriftRunsFromMinusToPlusOverTheRun) {
  RunSpec spec = quiet_run(Robot::kSwpc4, 100.0, {TourSegment{0.0, 0.0, Twist{}}});
  set_outside_effect(spec, "gyro_drift.rad_s=0.004");
  for (const RunRow& r : simulate(spec).rows) {
    EXPECT_NEAR(r.gyro_wz_radps, 0.004 * (2.0 * r.t_s / 100.0 - 1.0), 1e-12);
  }
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(EffectNames, BadAssignmentsAreRefusedWithTheProblemNamed) {
  RunSpec docent;
  RunSpec swpc;
  swpc.robot = Robot::kSwpc4;
  EXPECT_EQ(message_of([&] { set_true_effect(docent, "gyro_bias.bias=1"); }),
            "gyro_bias.bias: unknown parameter (expected: bias_rad_s)");
  EXPECT_EQ(message_of([&] { set_true_effect(docent, "gyro_scale.scale=3"); }),
            "gyro_scale.scale=3: outside [0.5, 2]");
  EXPECT_EQ(message_of([&] { set_true_effect(docent, "gyro_bias"); }),
            "gyro_bias: expected NAME.PARAM=VALUE");
  EXPECT_EQ(message_of([&] { set_true_effect(docent, "gyro_bias.bias_rad_s=abc"); }),
            "gyro_bias.bias_rad_s=abc: 'abc' is not a number");
  EXPECT_EQ(message_of([&] {
              set_true_effect(swpc, "track_width.scale=1.1");
            }).rfind("track_width: not an effect of the swpc4 robot (effects: gyro_bias, ", 0),
            0U);
  EXPECT_EQ(message_of([&] {
              set_true_effect(docent, "steering_offset.module_1_rad=0.1");
            }).rfind("steering_offset: not an effect of the docent robot", 0),
            0U);
  EXPECT_EQ(
      message_of([&] { set_true_effect(docent, "warp.drive=1"); })
          .rfind("warp: unknown effect (effects: gyro_bias, gyro_scale, wheel_radius, track_width",
                 0),
      0U);
  EXPECT_EQ(message_of([&] { set_outside_effect(docent, "eccentric_wheel.wheel=1.5"); }),
            "eccentric_wheel.wheel=1.5: expected a whole number");
  EXPECT_EQ(message_of([&] { set_outside_effect(docent, "eccentric_wheel.wheel=3"); }),
            "eccentric_wheel.wheel=3: outside [0, 2]");
  EXPECT_EQ(message_of([&] { set_true_effect(swpc, "wheel_radius.module_5_scale=1"); }),
            "wheel_radius.module_5_scale: unknown parameter (expected: module_1_scale, "
            "module_2_scale, module_3_scale, module_4_scale)");
}

TEST(EffectNames, InvalidSpecsAreRefusedWithTheFieldNamed) {
  RunSpec spec;
  spec.duration_s = 1.0;
  EXPECT_EQ(message_of([&] { validate(spec); }), "duration_s=1: expected within [2, 3600]");
  spec = RunSpec{};
  spec.steering = Steering::kSelfAligning;
  EXPECT_EQ(message_of([&] { validate(spec); }),
            "steering: self_aligning applies to the swpc4 robot only");
  spec = RunSpec{};
  spec.tour = step_tour(1.0, Twist{0.0, 0.2, 0.0});
  EXPECT_EQ(message_of([&] { validate(spec); }),
            "tour segment 2: vy_mps=0.2: the docent cannot move sideways");
  spec = RunSpec{};
  spec.truth.gyro_scale = 5.0;
  EXPECT_EQ(message_of([&] { validate(spec); }), "truth: gyro_scale.scale=5: outside [0.5, 2]");
}

TEST(ExpectedEffects, ListTheLibraryEffectsWithAllTheirParameters) {
  RunSpec spec;
  EXPECT_TRUE(expected_effects(spec).empty());

  spec.robot = Robot::kSwpc4;
  set_true_effect(spec, "wheel_radius.module_2_scale=0.995");
  std::vector<ExpectedEffect> e = expected_effects(spec);
  ASSERT_EQ(e.size(), 1U);
  EXPECT_EQ(e[0].effect, "wheel_radius");
  ASSERT_EQ(e[0].params.size(), 4U);
  EXPECT_EQ(e[0].params[1].key, "module_2_scale");
  EXPECT_EQ(e[0].params[1].value, 0.995);
  EXPECT_EQ(e[0].params[0].value, 1.0);
}

TEST(ExpectedEffects, LimitsTheModelLeavesOutAreNamed) {
  RunSpec docent;
  docent.model_limits = ModelLimits::kNone;
  std::vector<ExpectedEffect> e = expected_effects(docent);
  ASSERT_EQ(e.size(), 1U);
  EXPECT_EQ(e[0].effect, "accel_limit");
  EXPECT_EQ(e[0].params[0].key, "linear_mps2");
  EXPECT_EQ(e[0].params[0].value, 0.6);
  EXPECT_EQ(e[0].params[1].key, "angular_radps2");
  EXPECT_EQ(e[0].params[1].value, 2.0);

  RunSpec swpc;
  swpc.robot = Robot::kSwpc4;
  swpc.model_limits = ModelLimits::kSteeringOnly;
  e = expected_effects(swpc);
  ASSERT_EQ(e.size(), 1U);
  EXPECT_EQ(e[0].effect, "accel_limit");

  swpc.model_limits = ModelLimits::kNone;
  e = expected_effects(swpc);
  ASSERT_EQ(e.size(), 2U);
  EXPECT_EQ(e[0].effect, "steering_rate_limit");
  EXPECT_EQ(e[0].params[0].value, 6.0);
  EXPECT_EQ(e[1].effect, "accel_limit");

  swpc.model_limits = ModelLimits::kAll;
  set_true_effect(swpc, "steering_rate_limit.radps=2");
  e = expected_effects(swpc);
  ASSERT_EQ(e.size(), 1U);
  EXPECT_EQ(e[0].effect, "steering_rate_limit");
  EXPECT_EQ(e[0].params[0].value, 2.0);
}

}  // namespace
}  // namespace swivel::independent
