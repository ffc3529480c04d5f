// SPDX-License-Identifier: Apache-2.0
// `swivel-lab simulate` end to end: the real executable writes logs that the reader accepts.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "swivel/differential/differential_kinematics.hpp"
#include "swivel/run_log.hpp"

namespace swivel {
namespace {

std::string source_dir() {
  const char* env = std::getenv("SWIVEL_SOURCE_DIR");
  return env != nullptr ? env : SWIVEL_SOURCE_DIR_FALLBACK;
}

class LabSimulateTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / "swivel_lab_simulate_test";
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Runs simulate with `args`; returns the exit status and keeps stderr in error_.
  int simulate(const std::string& args, const std::string& out) {
    const std::string err = (dir_ / "stderr.txt").string();
    const std::string cmd = std::string(SWIVEL_LAB_EXE) + " simulate " + args + " --out " +
                            (dir_ / out).string() + " >/dev/null 2>" + err;
    // The shell redirects the tool's output. NOLINTNEXTLINE(cert-env33-c)
    const int status = std::system(cmd.c_str());
    std::ifstream in(err);
    std::stringstream text;
    text << in.rdbuf();
    error_ = text.str();
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  static std::string robot(const std::string& name) {
    return source_dir() + "/config/robots/" + name;
  }
  std::string read(const std::string& name) {
    std::ifstream in(dir_ / name);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

  std::filesystem::path dir_;
  std::string error_;
};

TEST_F(LabSimulateTest, DifferentialLogDeadReckonsOntoItsMotionCapture) {
  ASSERT_EQ(simulate("--model " + robot("docent.yaml") +
                         " --trajectory stop-and-go --duration 11 --noise none",
                     "run.csv"),
            0)
      << error_;
  const RunLog log = read_run_log((dir_ / "run.csv").string());
  EXPECT_EQ(log.header.drivetrain, DrivetrainKind::kDifferential);
  ASSERT_EQ(log.samples.size(), 1101U);
  EXPECT_DOUBLE_EQ(log.samples.back().t_s, 11.0);
  // Encoder dead reckoning with the (true = nominal) model lands on the truth columns.
  const DifferentialParams p{0.075, 0.075, 0.40};
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
  for (std::size_t k = 1; k < log.samples.size(); ++k) {
    const Pose2 d = differential::forward_increment(
        p, log.samples[k].wheel_rad[0] - log.samples[k - 1].wheel_rad[0],
        log.samples[k].wheel_rad[1] - log.samples[k - 1].wheel_rad[1]);
    x += std::cos(yaw) * d.x_m - std::sin(yaw) * d.y_m;
    y += std::sin(yaw) * d.x_m + std::cos(yaw) * d.y_m;
    yaw += d.yaw_rad;
  }
  ASSERT_TRUE(log.samples.back().has_truth);
  EXPECT_NEAR(log.samples.back().truth.x_m, 2.8, 1e-3);  // two bursts of 3.5 s at 0.4 m/s
  EXPECT_NEAR(x, log.samples.back().truth.x_m, 2e-4);    // about one encoder count of travel
  EXPECT_NEAR(y, log.samples.back().truth.y_m, 1e-6);
}

TEST_F(LabSimulateTest, HiddenGyroBiasShowsInTheLogOnly) {
  ASSERT_EQ(simulate("--model " + robot("docent.yaml") +
                         " --trajectory straight --duration 2 --noise none "
                         "--effect gyro_bias.bias_rad_s=0.006",
                     "biased.csv"),
            0)
      << error_;
  const std::string text = read("biased.csv");
  EXPECT_EQ(text.find("gyro_bias"), std::string::npos);  // the log does not give it away
  const RunLog log = read_run_log((dir_ / "biased.csv").string());
  for (std::size_t k = 1; k < log.samples.size(); ++k) {
    EXPECT_NEAR(log.samples[k].gyro_wz_radps, 0.006, 1e-12);
  }
}

// The simulated gyro is read once a row and reports the mean rate since the previous read:
// the log says so (swivel/run_log.hpp), and its rows times their periods add up to the
// heading the motion capture saw, exactly, through the square's corner.
TEST_F(LabSimulateTest, GyroColumnIsTheDeclaredMeanOverEachRow) {
  ASSERT_EQ(simulate("--model " + robot("docent.yaml") +
                         " --trajectory square --duration 20 --noise none",
                     "square.csv"),
            0)
      << error_;
  EXPECT_NE(read("square.csv").find("\n# gyro_wz: mean over the row\n"), std::string::npos);
  const RunLog log = read_run_log((dir_ / "square.csv").string());
  ASSERT_TRUE(log.header.gyro_mean_over_row);
  ASSERT_TRUE(log.samples.back().has_truth);
  double heading = log.samples.front().truth.yaw_rad;
  double turned = 0.0;
  double largest_error = 0.0;
  for (std::size_t k = 1; k < log.samples.size(); ++k) {
    const RunLogSample& s = log.samples[k];
    heading += s.gyro_wz_radps * (s.t_s - log.samples[k - 1].t_s);
    turned += std::abs(s.gyro_wz_radps) * (s.t_s - log.samples[k - 1].t_s);
    if (!s.has_truth) continue;
    const double error = std::remainder(heading - s.truth.yaw_rad, 2.0 * std::numbers::pi);
    largest_error = std::max(largest_error, std::abs(error));
  }
  EXPECT_GT(turned, 1.5) << "a quarter turn at the corner";
  EXPECT_LT(largest_error, 1e-9);
}

TEST_F(LabSimulateTest, SwpcCalibrationRunIsDeterministicPerSeed) {
  const std::string args = "--model " + robot("swpc4.yaml") +
                           " --trajectory calibration --locked-module 3 --locked-steer-deg 165 "
                           "--duration 5 --seed 11";
  ASSERT_EQ(simulate(args, "a.csv"), 0) << error_;
  ASSERT_EQ(simulate(args, "b.csv"), 0) << error_;
  ASSERT_EQ(simulate(args + "0", "c.csv"), 0) << error_;
  EXPECT_EQ(read("a.csv"), read("b.csv"));
  EXPECT_NE(read("a.csv"), read("c.csv"));
  const RunLog log = read_run_log((dir_ / "a.csv").string());
  EXPECT_EQ(log.header.module_count, 4U);
  EXPECT_NEAR(log.samples.back().steer_rad[2], 165.0 * std::numbers::pi / 180.0, 2e-3);  // locked
  EXPECT_EQ(log.samples.back().wheel_rad[2], 0.0);
  EXPECT_GT(log.samples.back().wheel_rad[0], 1.0);  // free wheels drive
}

TEST_F(LabSimulateTest, ErrorsAreReportedWithNonZeroStatus) {
  EXPECT_EQ(simulate("--model " + robot("docent.yaml") + " --trajectory strafe", "x.csv"), 1);
  EXPECT_NE(error_.find("needs an omnidirectional (swpc) robot"), std::string::npos) << error_;
  EXPECT_EQ(
      simulate("--model " + robot("swpc4.yaml") + " --effect wheel_radius.left_scale=1.1", "x.csv"),
      1);
  EXPECT_NE(error_.find("effects.wheel_radius.left_scale: unknown parameter"), std::string::npos)
      << error_;
  EXPECT_EQ(
      simulate("--model " + robot("swpc4.yaml") + " --trajectory calibration --locked-module 5",
               "x.csv"),
      1);
  EXPECT_NE(error_.find("--locked-module: expected 1..4, got 5"), std::string::npos) << error_;
}

}  // namespace
}  // namespace swivel
