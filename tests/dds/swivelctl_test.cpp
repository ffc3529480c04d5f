// SPDX-License-Identifier: Apache-2.0
// swivelctl as a user runs it: a separate process against daemons' bridges on the domain.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "dds_test_util.hpp"
#include "ros2_interfaces.h"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/run_sample_publisher.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/run_log.hpp"

namespace swivel::dds {
namespace {

using test::unique_robot_id;

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
  [[nodiscard]] std::vector<std::string> lines() const {
    std::vector<std::string> result;
    std::istringstream in(out);
    for (std::string line; std::getline(in, line);) result.push_back(line);
    return result;
  }
};

RunResult swivelctl(const std::string& args) {
  const std::string err_file =
      ::testing::TempDir() + "swivelctl_err_" + std::to_string(::getpid()) + ".txt";
  const std::string command = std::string(SWIVELCTL_PATH) + " " + args + " 2>" + err_file;
  RunResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  while (const std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe))
    result.out.append(buffer, n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream err(err_file);
  result.err.assign(std::istreambuf_iterator<char>(err), {});
  std::remove(err_file.c_str());
  return result;
}

// A daemon stand-in: a bridge over a fake loop whose pose advances each cycle, with
// diagnostics and a reload counter.
class FakeDaemon {
 public:
  explicit FakeDaemon(const std::string& robot, DdsOptions options = {}) {
    options.diagnostics_rate_hz = 10.0;
    bridge_ = std::make_unique<DdsBridge>(
        options, robot,
        DdsCallbacks{.read_state =
                         [this](StateSnapshot& s) {
                           s = StateSnapshot{};
                           s.cycle = ++cycle_;
                           s.stamp_s = swivel::monotonic_s();
                           s.estimate.pose.x_m = 0.001 * static_cast<double>(cycle_);
                           s.mode = LoopMode::kVelocity;
                           std::snprintf(s.localization_plugin.data(), s.localization_plugin.size(),
                                         "raw_eg");
                           return true;
                         },
                     .on_command =
                         [this](const VelocityCommand& c) {
                           const std::scoped_lock lock(mutex_);
                           commands_.push_back(c);
                           return true;
                         },
                     .read_diagnostics =
                         [this] {
                           DiagnosticsSample d;
                           d.loop_rate_hz = 1000.0;
                           d.measured_rate_hz = 1000.0;
                           d.hardware_plugin = "sim";
                           d.drivetrain_plugin = "differential";
                           d.localization_plugin = "raw_eg";
                           d.reload_count = reloads_.load();
                           d.last_reload_ok = true;
                           d.last_reload_result = reloads_ > 0 ? "localization: kalman" : "";
                           return d;
                         },
                     .on_request =
                         [this](const RequestSample& r) {
                           // Answered as swiveld answers: a Reply with the request's id.
                           ReplySample reply{r.request_id, r.verb, true, ""};
                           if (r.verb == "reload") {
                             ++reloads_;
                             reply.text = "applied localization raw_eg -> kalman";
                           } else if (r.verb == "clear") {
                             reply.ok = false;
                             reply.text =
                                 "refused: hardware_error persists (sim: hardware not answering)";
                           }
                           bridge_->publish_reply(reply);
                         },
                     .on_set_pose =
                         [this](const SetPoseSample& p) {
                           {
                             const std::scoped_lock lock(mutex_);
                             poses_.push_back(p);
                           }
                           bridge_->publish_reply({p.request_id, "set_pose", true, "pose set"});
                         }});
    bridge_->start();
  }

  std::vector<VelocityCommand> commands() {
    const std::scoped_lock lock(mutex_);
    return commands_;
  }
  std::vector<SetPoseSample> poses() {
    const std::scoped_lock lock(mutex_);
    return poses_;
  }
  [[nodiscard]] dds_entity_t participant() const { return bridge_->participant(); }

 private:
  std::atomic<std::uint64_t> cycle_{0};
  std::atomic<std::uint32_t> reloads_{0};
  std::mutex mutex_;
  std::vector<VelocityCommand> commands_;
  std::vector<SetPoseSample> poses_;
  std::unique_ptr<DdsBridge> bridge_;
};

TEST(Swivelctl, EchoPrintsStateAsJsonLines) {
  const std::string robot = unique_robot_id("echo");
  FakeDaemon daemon(robot);

  const RunResult r = swivelctl("echo state --robot " + robot + " --count 3 --json --timeout 10");

  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lines = r.lines();
  ASSERT_EQ(lines.size(), 3U) << r.out;
  double last_x = -1.0;
  for (const auto& line : lines) {
    const auto j = nlohmann::json::parse(line);
    EXPECT_EQ(j["robot_id"], robot);
    EXPECT_EQ(j["mode"], "velocity");
    EXPECT_EQ(j["localization_plugin"], "raw_eg");
    EXPECT_GT(j["pose"]["x_m"].get<double>(), last_x);  // samples arrive in order
    last_x = j["pose"]["x_m"].get<double>();
  }
}

TEST(Swivelctl, EchoPrintsDiagnosticsLines) {
  const std::string robot = unique_robot_id("echo_diag");
  FakeDaemon daemon(robot);

  const RunResult r = swivelctl("echo diagnostics --robot " + robot + " --count 1 --timeout 10");

  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(r.lines().size(), 1U);
  EXPECT_EQ(r.out.rfind(robot + " rate=1000.0/1000.0Hz", 0), 0U) << r.out;
  EXPECT_NE(r.out.find("plugins=sim/differential/raw_eg"), std::string::npos) << r.out;
}

TEST(Swivelctl, DriveStreamsCommandsAndEndsWithAStop) {
  const std::string robot = unique_robot_id("drive");
  FakeDaemon daemon(robot);

  const RunResult r =
      swivelctl("drive 0.3 -0.1 0.5 --for 0.5 --rate-hz 20 --timeout 10 --robot " + robot);

  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(test::wait_for([&] { return daemon.commands().size() >= 2; }));
  const auto commands = daemon.commands();
  EXPECT_DOUBLE_EQ(commands.front().twist.vx_mps, 0.3);
  EXPECT_DOUBLE_EQ(commands.front().twist.vy_mps, -0.1);
  EXPECT_DOUBLE_EQ(commands.front().twist.wz_radps, 0.5);
  EXPECT_DOUBLE_EQ(commands.back().twist.vx_mps, 0.0);
  EXPECT_DOUBLE_EQ(commands.back().twist.wz_radps, 0.0);
  // 0.5 s at 20 Hz: about 10 commands plus the stop; a generous band, not a timing test.
  EXPECT_GE(commands.size(), 3U);
  EXPECT_LE(commands.size(), 13U);
}

TEST(Swivelctl, StatusListsEveryDaemonOfAFleet) {
  const std::string stem = unique_robot_id("fleet");
  const FakeDaemon a(stem + "_a");
  const FakeDaemon b(stem + "_b");
  const FakeDaemon c(stem + "_c");

  const RunResult r = swivelctl("status --json --timeout 10");

  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const std::string& id : {stem + "_a", stem + "_b", stem + "_c"}) {
    ASSERT_TRUE(j.contains(id)) << r.out;
    EXPECT_EQ(j[id]["localization_plugin"], "raw_eg");
    EXPECT_EQ(j[id]["mode"], "velocity");
    EXPECT_EQ(j[id]["diagnostics"]["plugins"]["drivetrain"], "differential");
  }
}

// A Nav2 on Jazzy (Twist) against the default TwistStamped cmd_vel: the robot would not
// move, and `swivelctl status` says why and what to set; the publish rate is in its row.
TEST(Swivelctl, StatusNamesACmdVelPublisherOfTheOtherType) {
  const std::string robot = unique_robot_id("mismatch");
  DdsOptions options;
  options.ros2.enabled = true;
  options.ros2.ros_namespace = robot;
  FakeDaemon daemon(robot, options);
  Participant nav2({0, tool_config_uri()});
  const dds_entity_t topic = create_topic(nav2.handle(), &geometry_msgs_msg_dds__Twist__desc,
                                          ("rt/" + robot + "/cmd_vel").c_str());
  const QosPtr qos = default_qos(10);
  ASSERT_GT(dds_create_writer(nav2.handle(), topic, qos.get(), nullptr), 0);
  const std::string warning =
      "a Twist publisher on /" + robot + "/cmd_vel; set dds.ros2.cmd_vel_stamped: false";

  RunResult table;
  ASSERT_TRUE(test::wait_for(
      [&] {
        table = swivelctl("status --timeout 10 --robot " + robot);
        return table.out.find(warning) != std::string::npos;
      },
      std::chrono::seconds(30)))
      << table.out << table.err;
  EXPECT_NE(table.out.find("  " + robot + ": " + warning + "\n"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("PUB_HZ"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("/100 "), std::string::npos) << table.out;  // of dds.publish_rate_hz

  const RunResult json = swivelctl("status --json --timeout 10 --robot " + robot);
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const auto j = nlohmann::json::parse(json.out);
  // On a busy machine a missed publish rate may be warned about beside it.
  EXPECT_NE(j[robot]["diagnostics"]["dds_warnings"].get<std::string>().find(warning),
            std::string::npos)
      << j[robot]["diagnostics"]["dds_warnings"];
  EXPECT_DOUBLE_EQ(j[robot]["diagnostics"]["publish_rate_hz"].get<double>(), 100.0);
}

TEST(Swivelctl, ReloadReportsTheDaemonsAnswer) {
  const std::string robot = unique_robot_id("reload");
  FakeDaemon daemon(robot);

  const RunResult r = swivelctl("reload --timeout 10 --robot " + robot);

  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, robot + ": reload applied: applied localization raw_eg -> kalman\n");
}

TEST(Swivelctl, ClearPrintsTheRefusalAndExitsOne) {
  const std::string robot = unique_robot_id("clear");
  FakeDaemon daemon(robot);

  const RunResult r = swivelctl("clear --timeout 10 --robot " + robot);

  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.out,
            robot + ": clear: refused: hardware_error persists (sim: hardware not answering)\n");
}

TEST(Swivelctl, SetPoseSendsThePoseAndItsSigmas) {
  const std::string robot = unique_robot_id("set_pose");
  FakeDaemon daemon(robot);

  const RunResult r =
      swivelctl("set-pose -1.5 2 -0.25 --sigma 0.1 0.2 0.05 --timeout 10 --robot " + robot);
  const RunResult bare = swivelctl("set-pose 3 4 0 --timeout 10 --robot " + robot);
  const RunResult bad = swivelctl("set-pose 3 4 0 --sigma 0.1 -0.2 0.05 --robot " + robot);

  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, robot + ": set-pose: pose set\n");
  ASSERT_EQ(bare.exit_code, 0) << bare.err;
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--sigma: standard deviations must be finite and >= 0"), std::string::npos)
      << bad.err;
  const auto poses = daemon.poses();
  ASSERT_EQ(poses.size(), 2U);
  EXPECT_EQ(poses[0].pose.pose.x_m, -1.5);
  EXPECT_EQ(poses[0].pose.pose.y_m, 2.0);
  EXPECT_EQ(poses[0].pose.pose.yaw_rad, -0.25);
  EXPECT_TRUE(poses[0].pose.has_covariance);
  EXPECT_NEAR(poses[0].pose.covariance[4], 0.04, 1e-15);
  EXPECT_FALSE(poses[1].pose.has_covariance);
}

// Run samples at 100 Hz (stamps on a synthetic clock, sent as time passes): every 100th
// sequence number has ten missing after it (the loop's ring lost them), every 100th sample
// carries a NaN wheel angle (a sensor fault cycle), some a fault code.
class FakeRunSamples {
 public:
  explicit FakeRunSamples(dds_entity_t participant, const std::string& robot)
      : publisher_(participant, robot, DrivetrainKind::kDifferential, 0.01,
                   [this](RunSample& r) { return next(r); }) {
    publisher_.start();
  }

 private:
  bool next(RunSample& r) {
    if (swivel::monotonic_s() < start_s_ + 0.01 * static_cast<double>(produced_)) return false;
    ++produced_;
    if (sequence_ % 100 == 50) sequence_ += 10;  // lost before they were published
    ++sequence_;
    r = RunSample{};
    r.sequence = sequence_;
    r.stamp_s = 1000.0 + 0.01 * static_cast<double>(sequence_);
    r.module_count = 2;
    r.command_twist = {0.2, 0.0, 0.1};
    r.wheel_angle_rad[0] = 0.05 * static_cast<double>(sequence_);
    r.wheel_angle_rad[1] = 0.06 * static_cast<double>(sequence_);
    if (sequence_ % 100 == 80) r.wheel_angle_rad[1] = std::nan("");
    r.gyro_wz_radps = 0.1;
    r.has_truth = sequence_ % 2 == 0;
    r.truth = {0.001 * static_cast<double>(sequence_), 0.0, 0.0};
    r.estimate = {0.0011 * static_cast<double>(sequence_), -0.5, 0.25};
    r.fault = sequence_ % 100 == 90 ? FaultCode::kCommandTimeout : FaultCode::kNone;
    return true;
  }

  double start_s_ = swivel::monotonic_s();
  std::uint64_t produced_ = 0;
  std::uint64_t sequence_ = 0;
  RunSamplePublisher publisher_;
};

TEST(Swivelctl, RecordWritesTheSamplesAndReportsGapsAndSkippedOnes) {
  const std::string robot = unique_robot_id("record");
  FakeDaemon daemon(robot);
  FakeRunSamples samples(daemon.participant(), robot);
  const std::string path = ::testing::TempDir() + "swivelctl_record_" + robot + ".csv";

  const RunResult r =
      swivelctl("record --out " + path + " --duration 2.5 --timeout 10 --robot " + robot);

  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lines = r.lines();
  ASSERT_FALSE(lines.empty());
  const std::string& summary = lines.back();
  ASSERT_NE(summary.find("to " + path + ": "), std::string::npos) << summary;
  std::smatch counts;
  ASSERT_TRUE(std::regex_search(
      summary, counts,
      std::regex(
          R"(^recorded (\d+) rows .*: (\d+) gaps \((\d+) samples missing\), (\d+) skipped)")))
      << summary;
  const unsigned long rows = std::stoul(counts[1].str());
  const unsigned long gaps = std::stoul(counts[2].str());
  const unsigned long missing = std::stoul(counts[3].str());
  const unsigned long skipped = std::stoul(counts[4].str());
  // 2.5 s of stamps: 250 sequence numbers, each a row, a missing sample or a skipped one,
  // and up to 10 more when the sample that ends the recording comes right after a gap (its
  // missing predecessors are counted: some of them may belong to the window).
  EXPECT_GE(gaps, 2U) << summary;
  EXPECT_EQ(missing, 10 * gaps) << summary;
  EXPECT_GE(skipped, 2U) << summary;
  EXPECT_GE(rows + missing + skipped, 249U) << summary;
  EXPECT_LE(rows + missing + skipped, 261U) << summary;

  const RunLog log = read_run_log(path);
  EXPECT_EQ(log.header.robot, robot);
  EXPECT_TRUE(log.header.estimate_columns);
  ASSERT_EQ(log.samples.size(), rows);
  bool saw_fault = false;
  for (std::size_t k = 0; k < log.samples.size(); ++k) {
    const RunLogSample& s = log.samples[k];
    if (k > 0) {
      EXPECT_GT(s.t_s, log.samples[k - 1].t_s);
    }
    EXPECT_TRUE(std::isfinite(s.wheel_rad[1]));
    EXPECT_EQ(s.cmd.wz_radps, 0.1);
    EXPECT_EQ(s.estimate.y_m, -0.5);
    EXPECT_EQ(s.estimate.yaw_rad, 0.25);
    saw_fault = saw_fault || s.fault_code == static_cast<std::uint16_t>(FaultCode::kCommandTimeout);
    // The stamps are 10 ms apart: wheel_l advances 0.05 rad per sample.
    EXPECT_NEAR(s.wheel_rad[0] - log.samples[0].wheel_rad[0], 5.0 * s.t_s, 1e-9);
  }
  EXPECT_TRUE(saw_fault);
  std::remove(path.c_str());
}

TEST(Swivelctl, ExitsNonZeroWhenNothingAnswers) {
  const std::string robot = unique_robot_id("nobody");

  const RunResult echo = swivelctl("echo state --robot " + robot + " --timeout 1");
  const RunResult drive = swivelctl("drive 0.1 0 0 --for 1 --timeout 1 --robot " + robot);
  const RunResult status = swivelctl("status --timeout 1 --robot " + robot);

  EXPECT_EQ(echo.exit_code, 1);
  EXPECT_NE(echo.err.find("no swivel_robot_state sample from robot '" + robot + "' within 1 s"),
            std::string::npos)
      << echo.err;
  EXPECT_EQ(drive.exit_code, 1);
  EXPECT_NE(drive.err.find("within 1 s"), std::string::npos) << drive.err;
  EXPECT_EQ(status.exit_code, 1);
  EXPECT_NE(status.err.find("no swiveld answered within 1 s"), std::string::npos) << status.err;
}

}  // namespace
}  // namespace swivel::dds
