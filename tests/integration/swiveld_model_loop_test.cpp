// SPDX-License-Identifier: Apache-2.0
// The model-gap loop closed on the robot (docs/lab.md "The loop on a live robot"): swiveld drives
// the simulated docent, whose true model hides a gyro bias and a wheel-radius asymmetry; it is
// recorded with `swivelctl record`, `swivel-lab gap` names what its model misses and writes
// model_augmented.yaml with it folded into the robot's own parameters, that model replaces the
// robot's and `swivelctl reload` applies it, and the same drive recorded again shows the
// daemon's own estimate (est_* columns) following the simulator's truth (truth_*) at least 3x
// closer. Real processes over loopback DDS, domain 68.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "process_util.hpp"
#include "swivel/pose_math.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_log.hpp"

namespace swivel::test {
namespace {

constexpr int kDomain = 68;
constexpr double kGyroBiasRadps = 0.004;
// The true wheels over the model's 0.075 m. Over the one drive recorded (about 1.5 m) an
// asymmetry of +-0.2 % once came out at 4.9 sigma, under the naming bar of 5: +-0.3 % is
// clear of it.
constexpr double kLeftScale = 0.997;
constexpr double kRightScale = 1.003;
// The script, looped: at rest, then a figure that turns both ways at several speeds.
constexpr double kRestS = 3.0;
constexpr double kMotionS = 7.0;
// A recording starting anywhere in the loop holds one whole drive from rest to rest, with the
// second it takes the limits to bring the robot to rest after it: a loop and a drive, and 2 s.
constexpr double kRecordS = kRestS + 2.0 * kMotionS + 2.0;

std::string write_setup(const std::string& dir, const std::string& robot) {
  std::string nominal = read_text(source_dir() + "/config/robots/docent.yaml");
  nominal.replace(nominal.find("name: docent"), std::string("name: docent").size(),
                  "name: " + robot);
  // Acceleration limits as a real base has (the gap workflow's own test robot, see
  // swiveld_record_test).
  nominal += "limits: {linear_acceleration_mps2: 0.6, angular_acceleration_radps2: 2.0}\n";
  std::ofstream(dir + "/" + robot + ".yaml") << nominal;
  // The robot as it really is: what the nominal model does not know.
  std::string truth = nominal;
  truth.replace(truth.find("effects: {}"), std::string("effects: {}").size(),
                "effects:\n  gyro_bias: {bias_rad_s: " + std::to_string(kGyroBiasRadps) +
                    "}\n  wheel_radius: {left_scale: " + std::to_string(kLeftScale) +
                    ", right_scale: " + std::to_string(kRightScale) + "}");
  std::ofstream(dir + "/truth.yaml") << truth;
  std::ofstream config(dir + "/swiveld.yaml");
  config << "loop: {rate_hz: 1000, realtime: false}\n"
         << "robot_model: " << robot << ".yaml\n"
         << "hardware: {plugin: sim, params: {seed: 11, true_model: truth.yaml}}\n"
         << "drivetrain: {plugin: differential, params: {max_wheel_rate_radps: 20.0}}\n"
         << "localization: {plugin: raw_eg, params: {heading_source: gyro}}\n"
         << "command:\n  timeout_s: 0.5\n  source: script\n  script:\n"
         << "    - {vx_mps: 0.0, vy_mps: 0.0, wz_radps: 0.0, duration_s: " << kRestS << "}\n"
         << "    - {vx_mps: 0.3, vy_mps: 0.0, wz_radps: 0.0, duration_s: 1.5}\n"
         << "    - {vx_mps: 0.3, vy_mps: 0.0, wz_radps: 0.6, duration_s: 1.5}\n"
         << "    - {vx_mps: 0.15, vy_mps: 0.0, wz_radps: -0.5, duration_s: 1.5}\n"
         << "    - {vx_mps: 0.0, vy_mps: 0.0, wz_radps: 0.8, duration_s: 1.0}\n"
         << "    - {vx_mps: 0.25, vy_mps: 0.0, wz_radps: -0.3, duration_s: 1.5}\n"
         << "status: {period_s: 1.0}\n"
         << "dds:\n  domain_id: " << kDomain << "\n  config: " << source_dir()
         << "/config/dds/loopback.xml\n";
  return dir + "/swiveld.yaml";
}

std::vector<std::string> ctl(std::vector<std::string> args, const std::string& robot) {
  for (const std::string& a :
       {std::string("--domain"), std::to_string(kDomain), std::string("--robot"), robot,
        std::string("--timeout"), std::string("10")}) {
    args.push_back(a);
  }
  return args;
}

// How far the daemon's estimate strays from the truth over the first whole motion of a
// recording: from the last row at rest before it to the first row at rest after it, the
// estimate's path laid on the truth's start (so what went before does not count).
struct DriveError {
  double rms_m = 0.0;
  double final_m = 0.0;
  double length_m = 0.0;  // of the true path, to check the drive happened
};

DriveError drive_error(const RunLog& log) {
  const auto moving = [&](std::size_t k) {
    const Twist2& c = log.samples[k].cmd;
    return c.vx_mps != 0.0 || c.vy_mps != 0.0 || c.wz_radps != 0.0;
  };
  std::size_t start = 0;
  while (start + 1 < log.samples.size() && !(!moving(start) && moving(start + 1))) ++start;
  std::size_t end = start + 1;
  while (end < log.samples.size() && moving(end)) ++end;
  DriveError e;
  if (start + 1 >= log.samples.size() || end >= log.samples.size()) {
    ADD_FAILURE() << log.source << ": no whole motion from rest to rest";
    return e;
  }
  // The limits ramp the robot down after the command ends: the rest takes 1 s more.
  end = std::min(log.samples.size() - 1, end + 100);
  const RunLogSample& a = log.samples[start];
  double sum = 0.0;
  for (std::size_t k = start; k <= end; ++k) {
    const RunLogSample& s = log.samples[k];
    const Pose2 predicted = compose(a.truth, between(a.estimate, s.estimate));
    const double error = std::hypot(predicted.x_m - s.truth.x_m, predicted.y_m - s.truth.y_m);
    sum += error * error;
    e.final_m = error;
    if (k > start) {
      const RunLogSample& p = log.samples[k - 1];
      e.length_m += std::hypot(s.truth.x_m - p.truth.x_m, s.truth.y_m - p.truth.y_m);
    }
  }
  e.rms_m = std::sqrt(sum / static_cast<double>(end - start + 1));
  return e;
}

TEST(SwiveldModelLoop, WhatTheGapWorkflowNamesReachesTheRobotsEstimate) {
  const std::string dir = make_test_dir("model_loop");
  const std::string robot = "it_loop";
  Child daemon(swiveld_exe(), {"--config", write_setup(dir, robot)});
  const ToolRun echo = swivelctl(ctl({"echo", "state", "--count", "1"}, robot));
  ASSERT_EQ(echo.exit_code, 0) << echo.err << daemon.err();

  // 1. Record the robot on its nominal model.
  const std::string before_run = dir + "/before.csv";
  const ToolRun before =
      swivelctl(ctl({"record", "--out", before_run, "--duration", std::to_string(kRecordS)}, robot),
                Seconds(kRecordS + 30.0));
  ASSERT_EQ(before.exit_code, 0) << before.out << before.err << daemon.err();

  // 2. The workflow with the model the daemon runs (the sensor question is the one about the
  //    odometry; the command question is not needed here).
  const std::string nominal = dir + "/" + robot + ".yaml";
  const std::string report = dir + "/report";
  Child gap(SWIVEL_LAB_EXE,
            {"gap", "--model", nominal, "--run", before_run, "--out", report, "--sensor-only"});
  ASSERT_EQ(gap.exit_code(Seconds(120)), 0) << gap.out() << gap.err();
  const auto j = nlohmann::json::parse(read_text(report + "/report.json"));
  ASSERT_EQ(j["verdicts"]["sensor_to_pose"], "named") << gap.out();
  const std::string augmented_text = read_text(report + "/model_augmented.yaml");
  const RobotModel augmented = parse_robot_model(augmented_text, "model_augmented.yaml");
  // Folded into the robot's own parameters: nothing the daemon could use is left in effects.
  EXPECT_NE(augmented_text.find("# folded: gyro_bias.bias_rad_s"), std::string::npos)
      << augmented_text;
  EXPECT_TRUE(augmented.effects.empty()) << augmented_text;
  for (const std::string& line : lines_of(augmented_text)) {
    if (line.rfind('#', 0) == 0) std::cout << "model_augmented.yaml: " << line << '\n';
  }
  EXPECT_NEAR(augmented.sensors.gyro.bias_rad_s, kGyroBiasRadps, 0.001) << augmented_text;
  // The radii too (with the gyro's heading their asymmetry moves this estimate little).
  EXPECT_NEAR(augmented.differential.wheel_radius_left_m, 0.075 * kLeftScale, 0.075 * 5e-4)
      << augmented_text;
  EXPECT_NEAR(augmented.differential.wheel_radius_right_m, 0.075 * kRightScale, 0.075 * 5e-4)
      << augmented_text;

  // 3. The augmented model replaces the robot's, applied by a reload with the robot at rest
  //    (the script rests kRestS between drives; a reload while it drives is refused: retried).
  write_by_rename(nominal, augmented_text);
  ToolRun reload;
  const auto deadline = Clock::now() + Seconds(kRestS + kMotionS + 10.0);
  do {
    reload = swivelctl(ctl({"reload"}, robot));
  } while (reload.exit_code != 0 && Clock::now() < deadline &&
           reload.out.find("applies with the robot at rest") != std::string::npos);
  ASSERT_EQ(reload.exit_code, 0) << reload.out << reload.err << daemon.err();
  EXPECT_NE(reload.out.find("applied robot_model " + nominal), std::string::npos) << reload.out;

  // 4. The same drive again.
  const std::string after_run = dir + "/after.csv";
  const ToolRun after =
      swivelctl(ctl({"record", "--out", after_run, "--duration", std::to_string(kRecordS)}, robot),
                Seconds(kRecordS + 30.0));
  ASSERT_EQ(after.exit_code, 0) << after.out << after.err << daemon.err();

  const DriveError e0 = drive_error(read_run_log(before_run));
  const DriveError e1 = drive_error(read_run_log(after_run));
  std::cout << "daemon estimate against the truth over one drive of " << e0.length_m
            << " m: RMS position error " << e0.rms_m << " m -> " << e1.rms_m << " m ("
            << e0.rms_m / e1.rms_m << "x), final " << e0.final_m << " m -> " << e1.final_m
            << " m\n";
  EXPECT_GT(e0.length_m, 1.0) << "the drive happened";
  EXPECT_NEAR(e1.length_m, e0.length_m, 0.1 * e0.length_m) << "the same drive";
  // RMS over the drive rather than the final error: a heading drift's position error does
  // not grow steadily along a path that turns both ways, and one end point can fall where it
  // happens to cross zero.
  EXPECT_GT(e0.rms_m, 3.0 * e1.rms_m);

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(Seconds(10)), 0) << daemon.err();
  if (HasFailure()) {
    std::cout << "kept for a look: " << dir << " (the runs, the report, the models)\n";
  } else {
    std::filesystem::remove_all(dir);
  }
}

}  // namespace
}  // namespace swivel::test
