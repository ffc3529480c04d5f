// SPDX-License-Identifier: Apache-2.0
// The daemon's calibration procedure run offline on the simulated world, end to end.

#include "swivel/calibration/simulated_procedure.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/calibration/monte_carlo.hpp"

namespace swivel::calibration {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

RobotModel design_robot() {
  RobotModel m;
  m.name = "swpc4";
  m.drivetrain = DrivetrainKind::kSwpc;
  m.modules = paper_design_modules();
  return m;
}

// The paper's calibrated values (Table 4) as the simulated robot's truth.
RobotModel table4_robot() {
  RobotModel m = design_robot();
  m.modules = paper_table4_modules();
  return m;
}

struct Errors {
  double position_m = 0.0;
  double delta_rad = 0.0;
  double d_m = 0.0;
  double r_m = 0.0;
};

Errors worst_errors(const CalibrationResult& result, const RobotModel& truth) {
  Errors e;
  for (std::size_t i = 0; i < truth.modules.size(); ++i) {
    const SwpcModuleParams& est = result.modules[i].params;
    const SwpcModuleParams& tru = truth.modules[i];
    e.position_m = std::max(e.position_m, std::hypot(est.x_m - tru.x_m, est.y_m - tru.y_m));
    e.delta_rad =
        std::max(e.delta_rad, std::abs(wrap_pi(est.steering_offset_rad - tru.steering_offset_rad)));
    e.d_m = std::max(e.d_m, std::abs(est.caster_offset_m - tru.caster_offset_m));
    e.r_m = std::max(e.r_m, std::abs(est.wheel_radius_m - tru.wheel_radius_m));
  }
  return e;
}

// Noise-free sensors with encoders fine enough not to matter.
RobotModel ideal_sensors(RobotModel truth) {
  truth.sensors.wheel_encoder_counts_per_rev = 1 << 24;
  truth.sensors.steering_encoder_counts_per_rev = 1 << 24;
  return truth;
}

TEST(SimulatedProcedureTest, RecordsTwoFullRunsPerModuleAsTheDaemonDoes) {
  const SimulatedProcedureOptions options;  // the daemon's defaults
  const SimulatedCalibration sc =
      run_simulated_calibration(design_robot(), table4_robot(), options);

  ASSERT_TRUE(sc.result.ok()) << sc.result.verdict.text();
  ASSERT_EQ(sc.input.runs.size(), 8U);
  for (std::size_t j = 0; j < sc.input.runs.size(); ++j) {
    const LockedRun& run = sc.input.runs[j];
    SCOPED_TRACE("run " + std::to_string(j));
    EXPECT_EQ(run.locked_module, j / 2);
    // Counter-clockwise by at least the procedure's 300 degrees, at most one sample more.
    const double turned = run.data.yaw_rad.back() - run.data.yaw_rad.front();
    EXPECT_GE(turned, options.procedure.rotation_rad);
    EXPECT_LT(turned, options.procedure.rotation_rad + 0.01);
    // Locked where the alignment brought it: the angle asked for, within its tolerance (the
    // steering encoder counts turns, so compare modulo one).
    EXPECT_LE(std::abs(wrap_pi(run.locked_steer_meas_rad -
                               options.procedure.locked_angles_meas_rad[j % 2])),
              options.procedure.align_tolerance_rad);
  }
  // Alignment, settling, 300 degrees at 0.3 rad/s and stopping, eight times.
  EXPECT_GT(sc.duration_s, 8 * (options.procedure.rotation_rad / 0.3 + 1.5));
  EXPECT_LT(sc.duration_s, 8 * (options.procedure.rotation_rad / 0.3 + 5.0));
}

TEST(SimulatedProcedureTest, NoiseFreeSensorsRecoverTheTrueParameters) {
  const RobotModel truth = ideal_sensors(table4_robot());
  SimulatedProcedureOptions options;
  options.sim.sensor_noise = false;

  const SimulatedCalibration sc = run_simulated_calibration(design_robot(), truth, options);

  ASSERT_TRUE(sc.result.ok()) << sc.result.verdict.text();
  const Errors e = worst_errors(sc.result, truth);
  // What is left is the simulator's 1 ms integration of the rotation.
  EXPECT_LT(e.position_m, 1e-6);
  EXPECT_LT(e.delta_rad, 1e-5);
  EXPECT_LT(e.d_m, 1e-6);
  // Torque-driven wheels roll as the rotation asks: every radius is observable in one pass.
  EXPECT_LT(e.r_m, 1e-6);
}

// A steering encoder that wraps where a locked module sits and flickers by a count there: its
// readings flip between the two ends of its range. The procedure unwraps them as a log's reader
// does, so the locked angle does not average to the middle, the lock does not seem to move a
// whole turn, and the calibration comes out as from an encoder that counts turns.
TEST(SimulatedProcedureTest, SteeringWrappedWhereALockSitsCalibratesAsUnwrapped) {
  SimulatedProcedureOptions options;
  options.steering_flicker_rad = 0.002;
  const SimulatedCalibration turns =
      run_simulated_calibration(design_robot(), table4_robot(), options);
  ASSERT_TRUE(turns.result.ok()) << turns.result.verdict.text();
  // The encoder's wrap put at the first lock's reading (a real encoder's is wherever it was
  // mounted): that lock reads on both sides of it.
  const LockedRun& first = turns.input.runs.front();
  const std::vector<double>& locked = first.data.steer_angle_rad[first.locked_module];
  const auto [low, high] = std::ranges::minmax(locked);
  ASSERT_LT(low, high) << "the lock's reading does not flicker";
  const double lock = 0.5 * (low + high);
  options.wrap_steering = true;
  options.steering_wrap_center_rad = lock + std::numbers::pi;
  const SimulatedCalibration wrapped =
      run_simulated_calibration(design_robot(), table4_robot(), options);
  ASSERT_TRUE(wrapped.result.ok()) << wrapped.result.verdict.text();

  ASSERT_EQ(turns.input.runs.size(), wrapped.input.runs.size());
  for (std::size_t j = 0; j < turns.input.runs.size(); ++j) {
    EXPECT_NEAR(wrap_pi(wrapped.input.runs[j].locked_steer_meas_rad -
                        turns.input.runs[j].locked_steer_meas_rad),
                0.0, 1e-9)
        << "run " << j;
  }
  for (std::size_t i = 0; i < turns.result.modules.size(); ++i) {
    const SwpcModuleParams& a = turns.result.modules[i].params;
    const SwpcModuleParams& b = wrapped.result.modules[i].params;
    EXPECT_NEAR(a.x_m, b.x_m, 1e-9) << "module " << i + 1;
    EXPECT_NEAR(a.y_m, b.y_m, 1e-9) << "module " << i + 1;
    EXPECT_NEAR(wrap_pi(a.steering_offset_rad - b.steering_offset_rad), 0.0, 1e-9)
        << "module " << i + 1;
    EXPECT_NEAR(a.wheel_radius_m, b.wheel_radius_m, 1e-9) << "module " << i + 1;
  }
}

TEST(SimulatedProcedureTest, VelocityDrivenWheelsSlipAndBiasTheRadii) {
  // The same procedure with the free wheels tracking rates from the design values: their
  // wrong ratios make the wheels slip against one another, which torque drive avoids.
  const RobotModel truth = ideal_sensors(table4_robot());
  SimulatedProcedureOptions options;
  options.sim.sensor_noise = false;
  options.procedure.wheel_drive = WheelDrive::kVelocity;

  const SimulatedCalibration sc = run_simulated_calibration(design_robot(), truth, options);

  ASSERT_TRUE(sc.result.ok()) << sc.result.verdict.text();
  const Errors e = worst_errors(sc.result, truth);
  EXPECT_GT(e.r_m, 0.1e-3);  // Table 4's radii differ by up to 1.6 mm; slip takes a share
  EXPECT_LT(e.r_m, 1.0e-3);
  EXPECT_LT(e.position_m, 1e-6);  // the pivots do not depend on the wheels
}

TEST(SimulatedProcedureTest, QuantizedEncodersLimitTheAccuracyToTheirResolution) {
  // 4096-count encoders, no other noise: a locked angle is known to half a count (0.044 deg),
  // which bounds delta's error; positions move by d times that angle (a few um).
  const RobotModel truth = table4_robot();
  SimulatedProcedureOptions options;
  options.sim.sensor_noise = false;

  const SimulatedCalibration sc = run_simulated_calibration(design_robot(), truth, options);

  ASSERT_TRUE(sc.result.ok()) << sc.result.verdict.text();
  const Errors e = worst_errors(sc.result, truth);
  const double half_count_rad = std::numbers::pi / 4096.0;
  EXPECT_LT(e.delta_rad, 2.0 * half_count_rad);
  EXPECT_LT(e.position_m, 0.020 * 2.0 * half_count_rad + 1e-6);
  EXPECT_LT(e.d_m, 0.020 * 2.0 * half_count_rad + 1e-6);
  EXPECT_LT(e.r_m, 0.01e-3);
}

TEST(SimulatedProcedureTest, DefaultNoiseErrorsMostlyWithinReportedUncertainty) {
  const RobotModel truth = table4_robot();
  int within = 0;
  int total = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SimulatedProcedureOptions options;
    options.sim.seed = seed * 100;
    const SimulatedCalibration sc = run_simulated_calibration(design_robot(), truth, options);
    ASSERT_TRUE(sc.result.ok()) << sc.result.verdict.text();
    for (std::size_t i = 0; i < 4; ++i) {
      const ModuleCalibration& mc = sc.result.modules[i];
      const SwpcModuleParams& t = truth.modules[i];
      const double err[] = {mc.params.x_m - t.x_m, mc.params.y_m - t.y_m,
                            wrap_pi(mc.params.steering_offset_rad - t.steering_offset_rad),
                            mc.params.caster_offset_m - t.caster_offset_m,
                            mc.params.wheel_radius_m - t.wheel_radius_m};
      const double sigma[] = {mc.sigma.x_m, mc.sigma.y_m, mc.sigma.steering_offset_rad,
                              mc.sigma.caster_offset_m, mc.sigma.wheel_radius_m};
      for (int k = 0; k < 5; ++k) {
        ASSERT_GT(sigma[k], 0.0);
        within += std::abs(err[k]) <= 2.0 * sigma[k] ? 1 : 0;
        ++total;
      }
      // Absolute sanity with 0.3 mm / 0.06 deg motion capture over 300-degree runs:
      // hundredths of a millimetre and of a degree.
      EXPECT_LT(std::hypot(err[0], err[1]), 0.1e-3);
      EXPECT_LT(std::abs(err[2]), 0.2 * kDeg);
      EXPECT_LT(std::abs(err[4]), 0.02e-3);
    }
  }
  // A 2-sigma interval holds ~95 % of Gaussian errors; "mostly" leaves room for 100 draws.
  EXPECT_GE(static_cast<double>(within) / total, 0.85) << within << " of " << total;
}

TEST(SimulatedProcedureTest, ImpossibleMotionIsRefusedWithAReason) {
  RobotModel nominal = design_robot();
  nominal.modules[1].x_m = nominal.modules[0].x_m;  // module 2's axis on module 1's pivot
  nominal.modules[1].y_m = nominal.modules[0].y_m - 0.005;
  try {
    run_simulated_calibration(nominal, table4_robot(), SimulatedProcedureOptions{});
    FAIL() << "expected a refusal";
  } catch (const ProcedureConfigError& e) {
    EXPECT_EQ(e.option(), "locked_angles_meas_rad");
    EXPECT_NE(std::string(e.what()).find("module 2 is too close to module 1's pivot"),
              std::string::npos)
        << e.what();
  }
}

TEST(SimulatedProcedureTest, MissingMotionCaptureStopsTheProcedureWithItsReason) {
  SimulatedProcedureOptions options;
  options.sim.motion_capture = false;
  try {
    run_simulated_calibration(design_robot(), table4_robot(), options);
    FAIL() << "expected the procedure to fail";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no motion capture within motion_capture_timeout_s"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace swivel::calibration
