// swivelctl as a user runs it: a separate process against daemons' bridges on the domain.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "dds_test_util.hpp"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"

namespace swivel::dds {
namespace {

using test::unique_robot_id;

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
  std::vector<std::string> lines() const {
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
  while (const std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) result.out.append(buffer, n);
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
  explicit FakeDaemon(const std::string& robot) {
    DdsOptions options;
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
  ASSERT_EQ(lines.size(), 3u) << r.out;
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
  ASSERT_EQ(r.lines().size(), 1u);
  EXPECT_EQ(r.out.rfind(robot + " rate=1000.0/1000.0Hz", 0), 0u) << r.out;
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
  EXPECT_GE(commands.size(), 3u);
  EXPECT_LE(commands.size(), 13u);
}

TEST(Swivelctl, StatusListsEveryDaemonOfAFleet) {
  const std::string stem = unique_robot_id("fleet");
  FakeDaemon a(stem + "_a"), b(stem + "_b"), c(stem + "_c");

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
  EXPECT_NE(bad.err.find("--sigma: standard deviations must be finite and >= 0"),
            std::string::npos)
      << bad.err;
  const auto poses = daemon.poses();
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0].pose.pose.x_m, -1.5);
  EXPECT_EQ(poses[0].pose.pose.y_m, 2.0);
  EXPECT_EQ(poses[0].pose.pose.yaw_rad, -0.25);
  EXPECT_TRUE(poses[0].pose.has_covariance);
  EXPECT_NEAR(poses[0].pose.covariance[4], 0.04, 1e-15);
  EXPECT_FALSE(poses[1].pose.has_covariance);
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
