// SPDX-License-Identifier: Apache-2.0
// Recording a live robot for the model-gap workflow: swiveld (simulated docent, driven by its
// script) publishes run samples, `swivelctl record` writes them as a run log, and
// `swivel-lab gap` with the robot's own model finds nothing missing. Real processes over
// loopback DDS, domains 66 and 67.

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
#include "swivel/run_log.hpp"

namespace swivel::test {
namespace {

constexpr double kRecordRateHz = 100.0;  // dds.run_samples_rate_hz's default
// The gap workflow needs at least 10 windows of 1 s; its pattern tests are only reliable on
// a few dozen (on 15 s runs of this robot one in three flagged a wheel-angle pattern).
constexpr double kDurationS = 30.0;

// The docent under another robot id, with acceleration limits as a real base has, driving a
// figure that turns both ways at several speeds: what the gap workflow needs to tell effects
// apart. The script starts with the robot at rest for 5 s, so that the recording starts
// from rest as the workflow's command replay does.
std::string write_setup(const std::string& dir, const std::string& robot, int domain,
                        const std::string& run_samples_rate, int loop_rate_hz = 1000) {
  std::string model = read_text(source_dir() + "/config/robots/docent.yaml");
  model.replace(model.find("name: docent"), std::string("name: docent").size(), "name: " + robot);
  model += "limits: {linear_acceleration_mps2: 0.6, angular_acceleration_radps2: 2.0}\n";
  std::ofstream(dir + "/" + robot + ".yaml") << model;
  std::ofstream config(dir + "/swiveld.yaml");
  config << "loop: {rate_hz: " << loop_rate_hz << ", realtime: false}\n"
         << "robot_model: " << robot << ".yaml\n"
         << "hardware: {plugin: sim, params: {seed: 5}}\n"
         << "drivetrain: {plugin: differential, params: {max_wheel_rate_radps: 20.0}}\n"
         << "localization: {plugin: raw_eg, params: {heading_source: gyro}}\n"
         << "command:\n  timeout_s: 0.5\n  source: script\n  script:\n"
         << "    - {vx_mps: 0.0, vy_mps: 0.0, wz_radps: 0.0, duration_s: 5.0}\n"
         << "    - {vx_mps: 0.3, vy_mps: 0.0, wz_radps: 0.0, duration_s: 2.0}\n"
         << "    - {vx_mps: 0.3, vy_mps: 0.0, wz_radps: 0.6, duration_s: 2.0}\n"
         << "    - {vx_mps: 0.15, vy_mps: 0.0, wz_radps: -0.5, duration_s: 2.5}\n"
         << "    - {vx_mps: 0.4, vy_mps: 0.0, wz_radps: 0.2, duration_s: 2.0}\n"
         << "    - {vx_mps: 0.0, vy_mps: 0.0, wz_radps: 0.8, duration_s: 1.5}\n"
         << "    - {vx_mps: 0.25, vy_mps: 0.0, wz_radps: -0.3, duration_s: 2.0}\n"
         << "status: {period_s: 1.0}\n"
         << "dds:\n  domain_id: " << domain << "\n  config: " << source_dir()
         << "/config/dds/loopback.xml\n";
  if (!run_samples_rate.empty()) config << "  run_samples_rate_hz: " << run_samples_rate << "\n";
  return dir + "/swiveld.yaml";
}

std::vector<std::string> ctl(std::vector<std::string> args, int domain, const std::string& robot) {
  for (const std::string& a :
       {std::string("--domain"), std::to_string(domain), std::string("--robot"), robot,
        std::string("--timeout"), std::string("10")}) {
    args.push_back(a);
  }
  return args;
}

// Waits until the daemon answers on DDS.
void wait_for_daemon(Child& daemon, int domain, const std::string& robot) {
  const ToolRun echo = swivelctl(ctl({"echo", "state", "--count", "1"}, domain, robot));
  ASSERT_EQ(echo.exit_code, 0) << echo.err << daemon.err();
}

TEST(SwiveldRecordOverDds, RecordsEverySampleAndTheGapWorkflowFindsNothingMissing) {
  const std::string dir = make_test_dir("record_dds");
  const std::string robot = "it_rec_dds";
  constexpr int kDomain = 66;
  Child daemon(swiveld_exe(), {"--config", write_setup(dir, robot, kDomain, "")});
  wait_for_daemon(daemon, kDomain, robot);

  const std::string run = dir + "/run.csv";
  const ToolRun record = swivelctl(
      ctl({"record", "--out", run, "--duration", std::to_string(kDurationS)}, kDomain, robot),
      Seconds(kDurationS + 30.0));
  ASSERT_EQ(record.exit_code, 0) << record.out << record.err << daemon.err();
  const auto lines = lines_of(record.out);
  ASSERT_GE(lines.size(), 2U) << "progress lines and a summary: " << record.out;
  EXPECT_NE(lines.front().find(robot + ": "), std::string::npos) << record.out;
  EXPECT_NE(lines.back().find("0 gaps (0 samples missing), 0 skipped"), std::string::npos)
      << record.out;

  const RunLog log = read_run_log(run);
  EXPECT_EQ(log.header.robot, robot);
  EXPECT_EQ(log.header.drivetrain, DrivetrainKind::kDifferential);
  EXPECT_TRUE(log.header.estimate_columns);
  // Every sample of [0, duration) at the record rate. The loop restarts its sample schedule
  // after a stall (realtime is off here and the machine shared), which may leave out a few;
  // a stamp's wake-up jitter may let one more in at the end.
  const auto expected = static_cast<std::size_t>(kDurationS * kRecordRateHz);
  EXPECT_GE(log.samples.size(), expected - expected / 100);
  EXPECT_LE(log.samples.size(), expected + 1);
  std::vector<double> steps_s;
  for (std::size_t k = 1; k < log.samples.size(); ++k) {
    const double dt = log.samples[k].t_s - log.samples[k - 1].t_s;
    ASSERT_GT(dt, 0.0) << "time not increasing at row " << k;
    // Only a stalled loop leaves a longer step (lost samples are counted as gaps above).
    EXPECT_LT(dt, 0.1) << "a hole at row " << k;
    steps_s.push_back(dt);
  }
  const auto middle = steps_s.begin() + static_cast<std::ptrdiff_t>(steps_s.size() / 2);
  std::nth_element(steps_s.begin(), middle, steps_s.end());
  EXPECT_NEAR(*middle, 1.0 / kRecordRateHz, 2e-4);
  const RunLogSample& first = log.samples.front();
  const RunLogSample& last = log.samples.back();
  ASSERT_EQ(first.cmd.vx_mps, 0.0) << "the recording must start at rest for the replay";
  EXPECT_EQ(record.err.find("is moving as the recording starts"), std::string::npos) << record.err;
  EXPECT_GT(last.wheel_rad[0] - first.wheel_rad[0], 40.0);  // about 6 m on 75 mm wheels
  EXPECT_GT(last.wheel_rad[1] - first.wheel_rad[1], 40.0);
  double max_turn_radps = 0.0;
  for (const RunLogSample& s : log.samples) {
    ASSERT_TRUE(s.has_truth) << "the simulator's true pose is on every row";
    EXPECT_EQ(s.fault_code, 0) << "at t=" << s.t_s;
    // The estimate columns are the daemon's estimate: the gyro dead reckoning stays close.
    EXPECT_LT(std::hypot(s.estimate.x_m - s.truth.x_m, s.estimate.y_m - s.truth.y_m), 0.05)
        << "at t=" << s.t_s;
    max_turn_radps = std::max(max_turn_radps, std::abs(s.gyro_wz_radps));
  }
  EXPECT_GT(max_turn_radps, 0.5) << "the script's turns are in the log";

  // The robot's own, correct model: the workflow must find no significant gap.
  const std::string report = dir + "/report";
  Child gap(SWIVEL_LAB_EXE,
            {"gap", "--model", dir + "/" + robot + ".yaml", "--run", run, "--out", report});
  ASSERT_EQ(gap.exit_code(Seconds(120)), 0) << gap.out() << gap.err();
  EXPECT_NE(gap.out().find("sensor to pose: no significant gap"), std::string::npos) << gap.out();
  EXPECT_NE(gap.out().find("command to motion: no significant gap"), std::string::npos)
      << gap.out();
  const auto verdicts = nlohmann::json::parse(read_text(report + "/report.json"))["verdicts"];
  EXPECT_EQ(verdicts["sensor_to_pose"], "no significant gap") << verdicts.dump();
  EXPECT_EQ(verdicts["command_to_motion"], "no significant gap") << verdicts.dump();

  // Ctrl-C ends a recording without --duration cleanly, the file complete and readable.
  const std::string interrupted = dir + "/interrupted.csv";
  Child until_ctrl_c(swivelctl_exe(), ctl({"record", "--out", interrupted}, kDomain, robot));
  const auto started = Clock::now();  // until its first row is in the file
  while (Clock::now() - started < Seconds(20) &&
         read_text(interrupted).find("\n0,") == std::string::npos) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(Seconds(1.5));
  until_ctrl_c.signal(SIGINT);
  ASSERT_EQ(until_ctrl_c.exit_code(Seconds(10)), 0) << until_ctrl_c.out() << until_ctrl_c.err();
  const RunLog partial = read_run_log(interrupted);
  EXPECT_GT(partial.samples.size(), 100U);
  EXPECT_NE(until_ctrl_c.out().find("0 gaps"), std::string::npos) << until_ctrl_c.out();

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(Seconds(10)), 0) << daemon.err();
  EXPECT_NE(daemon.err().find("run samples published, 0 lost"), std::string::npos) << daemon.err();
  // A recording that failed is kept: the run and the report are what tells why.
  if (HasFailure()) {
    std::cerr << "kept for diagnosis: " << dir << "\n";
  } else {
    std::filesystem::remove_all(dir);
  }
}

TEST(SwiveldRecordOverDds, RefusalsNameTheProblem) {
  const std::string dir = make_test_dir("record_refusals");
  const std::string robot = "it_rec_off";
  constexpr int kDomain = 67;

  // A file that cannot be written: refused before anything waits.
  const ToolRun no_dir = swivelctl(
      ctl({"record", "--out", dir + "/missing/run.csv", "--duration", "1"}, kDomain, robot));
  EXPECT_EQ(no_dir.exit_code, 1);
  EXPECT_NE(no_dir.err.find("missing/run.csv: cannot open for writing"), std::string::npos)
      << no_dir.err;

  // A daemon with run samples off: it answers, but sends nothing to record.
  Child daemon(swiveld_exe(), {"--config", write_setup(dir, robot, kDomain, "off")});
  wait_for_daemon(daemon, kDomain, robot);
  std::vector<std::string> args =
      ctl({"record", "--out", dir + "/run.csv", "--duration", "1"}, kDomain, robot);
  args.back() = "2";  // --timeout 2
  const ToolRun off = swivelctl(args);
  EXPECT_EQ(off.exit_code, 1);
  EXPECT_NE(off.err.find("dds.run_samples_rate_hz"), std::string::npos) << off.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/run.csv")) << "no empty log left behind";
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(Seconds(10)), 0) << daemon.err();

  // A rate above the loop's is a configuration error naming the key.
  const std::string config = write_setup(dir, robot, kDomain, "500", 200);
  Child check(swiveld_exe(), {"--config", config, "--check"});
  EXPECT_EQ(check.exit_code(Seconds(20)), 1);
  EXPECT_NE(check.err().find("dds.run_samples_rate_hz: expected at most loop.rate_hz (200 Hz), "
                             "got 500"),
            std::string::npos)
      << check.err();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace swivel::test
