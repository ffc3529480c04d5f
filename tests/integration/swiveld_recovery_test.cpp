// SPDX-License-Identifier: Apache-2.0
// The recovery verbs as an operator uses them: swivelctl against a running swiveld over DDS
// (loopback), each answered with the daemon's reply and an exit code.

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "process_util.hpp"

namespace swivel::test {
namespace {

using nlohmann::json;

// swiveld on the simulated docent robot under its own robot id and DDS domain.
class Daemon {
 public:
  Daemon(const std::string& robot, int domain, const std::string& hardware,
         const std::string& localization)
      : robot_(robot), domain_(domain), dir_(make_test_dir("recovery_" + robot)) {
    std::string model = read_text(source_dir() + "/config/robots/docent.yaml");
    model.replace(model.find("name: docent"), std::string("name: docent").size(), "name: " + robot);
    std::ofstream(dir_ + "/robot.yaml") << model;
    write(hardware, localization);
    child_ = std::make_unique<Child>(swiveld_exe(), std::vector<std::string>{"--config", config()});
  }
  ~Daemon() {
    child_.reset();
    std::filesystem::remove_all(dir_);
  }
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;
  Daemon(Daemon&&) = delete;
  Daemon& operator=(Daemon&&) = delete;

  [[nodiscard]] std::string config() const { return dir_ + "/swiveld.yaml"; }
  void write(const std::string& hardware, const std::string& localization) const {
    std::ostringstream y;
    y << "loop: {rate_hz: 500, realtime: false}\n"
      << "robot_model: robot.yaml\n"
      << "plugin_path: [" << build_dir() << "/lib/swivel/test_plugins]\n"
      << "hardware: " << hardware << "\n"
      << "drivetrain: {plugin: differential}\n"
      << "localization: " << localization << "\n"
      << "command: {timeout_s: 0.5, source: none}\n"
      << "dds:\n  domain_id: " << domain_ << "\n  config: " << source_dir()
      << "/config/dds/loopback.xml\n";
    write_by_rename(config(), y.str());
  }

  [[nodiscard]] ToolRun ctl(std::vector<std::string> args) const {
    for (const std::string& a :
         {std::string("--robot"), robot_, std::string("--domain"), std::to_string(domain_),
          std::string("--timeout"), std::string("10")}) {
      args.push_back(a);
    }
    return swivelctl(args);
  }
  [[nodiscard]] json state() const {
    const ToolRun run = ctl({"echo", "state", "--json", "--count", "1"});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return run.out.empty() ? json{} : json::parse(lines_of(run.out).front());
  }
  // Polls the state until `done` holds (10 s at most).
  json wait_for(const std::function<bool(const json&)>& done) const {
    json s;
    const auto deadline = Clock::now() + Seconds(10);
    while (Clock::now() < deadline) {
      s = state();
      if (done(s)) return s;
    }
    ADD_FAILURE() << "state never reached: " << s.dump();
    return s;
  }
  Child& process() { return *child_; }
  [[nodiscard]] const std::string& robot() const { return robot_; }
  [[nodiscard]] int domain() const { return domain_; }

 private:
  std::string robot_;
  int domain_;
  std::string dir_;
  std::unique_ptr<Child> child_;
};

// A stall of the simulated hardware from 1 s to 6 s of sim time: a clear during it is
// refused with the cause, one after it is accepted, and the robot drives again. A command
// stream that ended with a stop leaves nothing to clear; one that went silent mid-motion is a
// timeout, and a clear of it is refused.
TEST(SwiveldRecovery, ClearIsRefusedWhileTheHardwareStallsAndAcceptedAfterwards) {
  Daemon daemon("it_clear", 73,
                "{plugin: sim, params: {faults: [{kind: stall, start_s: 1.0, duration_s: 5.0}]}}",
                "{plugin: raw_eg}");
  const json stalled =
      daemon.wait_for([](const json& s) { return s["fault"] == "hardware_error"; });
  EXPECT_EQ(stalled["mode"], "safe_stop");

  const ToolRun refused = daemon.ctl({"clear"});
  EXPECT_EQ(refused.exit_code, 1) << refused.out << refused.err;
  EXPECT_EQ(refused.out, daemon.robot() +
                             ": clear: refused: hardware_error persists (sim: hardware not "
                             "answering)\n");

  // The stall ends at 6 s of sim time; a clear after that is accepted.
  ToolRun cleared;
  const auto deadline = Clock::now() + Seconds(20);
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    cleared = daemon.ctl({"clear"});
  } while (cleared.exit_code != 0 && Clock::now() < deadline);
  EXPECT_EQ(cleared.exit_code, 0) << cleared.out << cleared.err;
  EXPECT_EQ(cleared.out,
            daemon.robot() + ": clear: cleared hardware_error (sim: hardware not answering)\n");
  EXPECT_EQ(daemon.state()["mode"], "idle");

  const ToolRun drive = daemon.ctl({"drive", "0.2", "0", "0", "--for", "1"});
  EXPECT_EQ(drive.exit_code, 0) << drive.err;
  EXPECT_GT(daemon.state()["truth"]["x_m"].get<double>(), 0.05);
  // The drive is over, its stream ended with a stop: past the timeout the robot is idle, which
  // is no fault.
  std::this_thread::sleep_for(Seconds(1.0));
  const json idle = daemon.state();
  EXPECT_EQ(idle["mode"], "idle") << idle.dump();
  EXPECT_EQ(idle["fault"], "none") << idle.dump();
  const ToolRun nothing = daemon.ctl({"clear"});
  EXPECT_EQ(nothing.exit_code, 0) << nothing.out << nothing.err;
  EXPECT_EQ(nothing.out, daemon.robot() + ": clear: nothing to clear\n");

  // A stream that goes silent inside a motion is a timeout, which a clear cannot end.
  {
    Child moving(swivelctl_exe(), {"drive", "0.2", "0", "0", "--robot", daemon.robot(), "--domain",
                                   std::to_string(daemon.domain()), "--timeout", "10"});
    daemon.wait_for([](const json& s) { return s["mode"] == "velocity"; });
    moving.signal(SIGKILL);  // no final stop
    moving.wait_for(Seconds(5));
  }
  daemon.wait_for([](const json& s) { return s["fault"] == "command_timeout"; });
  const ToolRun absent = daemon.ctl({"clear"});
  EXPECT_EQ(absent.exit_code, 1);
  EXPECT_EQ(absent.out, daemon.robot() +
                            ": clear: refused: command_timeout persists (velocity command timed "
                            "out): no fresh velocity command; the next one resumes by itself\n");
  EXPECT_TRUE(daemon.process().alive());
}

// set-pose through DDS into the active localization (kalman keeps a covariance).
TEST(SwiveldRecovery, SetPoseMovesTheEstimateAndItsCovariance) {
  Daemon daemon("it_set_pose", 74, "{plugin: sim, params: {motion_capture: false}}",
                "{plugin: kalman, params: {mode: ekf}}");
  daemon.wait_for([](const json& s) { return s.contains("pose"); });

  const ToolRun set = daemon.ctl({"set-pose", "3", "-1.5", "1.2", "--sigma", "0.1", "0.2", "0.05"});
  ASSERT_EQ(set.exit_code, 0) << set.out << set.err;
  EXPECT_EQ(set.out, daemon.robot() +
                         ": set-pose: pose set to x=3.000 m y=-1.500 m yaw=1.200 rad, sigma "
                         "x=0.1 m y=0.2 m yaw=0.05 rad (localization kalman)\n");
  const json s = daemon.state();
  EXPECT_NEAR(s["pose"]["x_m"].get<double>(), 3.0, 1e-3);  // standing still
  EXPECT_NEAR(s["pose"]["y_m"].get<double>(), -1.5, 1e-3);
  EXPECT_NEAR(s["pose"]["yaw_rad"].get<double>(), 1.2, 1e-3);
  ASSERT_TRUE(s["has_covariance"].get<bool>());
  EXPECT_NEAR(s["pose_covariance"][0].get<double>(), 0.01, 2e-3);
  EXPECT_NEAR(s["pose_covariance"][4].get<double>(), 0.04, 2e-3);
  EXPECT_EQ(s["fault"], "none");

  const ToolRun bad = daemon.ctl({"set-pose", "1", "2", "nan"});
  EXPECT_EQ(bad.exit_code, 2);
}

// Reload to a localization that refuses the hand-over: swivelctl reload exits 1 with the
// plugin's reason, the robot keeps its localization and no fault is raised.
TEST(SwiveldRecovery, ReloadReportsARefusedHandOverAndKeepsTheRunningLocalization) {
  Daemon daemon("it_rollback", 75, "{plugin: sim}", "{plugin: raw_eg}");
  daemon.wait_for([](const json& s) { return s.contains("pose"); });
  daemon.write("{plugin: sim}", "{plugin: refuses_hand_over}");

  const ToolRun reload = daemon.ctl({"reload"});
  EXPECT_EQ(reload.exit_code, 1) << reload.out << reload.err;
  EXPECT_NE(reload.out.find(": reload rejected: rejected: "), std::string::npos) << reload.out;
  EXPECT_NE(reload.out.find("plugin 'refuses_hand_over' refused the hand-over: no map to place "
                            "the pose in (planted refusal); 'raw_eg' stays active"),
            std::string::npos)
      << reload.out;
  const json s = daemon.state();
  EXPECT_EQ(s["localization_plugin"], "raw_eg");
  EXPECT_EQ(s["fault"], "none");
  EXPECT_EQ(s["fault_count"], 0);
  EXPECT_TRUE(daemon.process().alive());
}

}  // namespace
}  // namespace swivel::test
