// SPDX-License-Identifier: Apache-2.0
// swiveld as users run it: real processes, real DDS on loopback (CYCLONEDDS_URI points at
// config/dds/loopback.xml and every daemon's dds.config names it too). Each test uses its
// own DDS domain and robot id so that parallel test runs do not see each other.

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "process_util.hpp"
#include "swivel/run_log.hpp"

namespace swivel::test {
namespace {

using nlohmann::json;

struct DaemonSetup {
  std::string robot = "docent";
  int domain = 0;
  double rate_hz = 500.0;
  std::string localization = "raw_eg";
  std::string localization_params = "{heading_source: gyro}";
  std::string command_source = "none";  // or "script" (driving forward at vx_mps)
  double script_vx_mps = 0.3;
  double script_wz_radps = 0.0;
};

// A copy of the docent model under another robot id (the DDS key).
std::string robot_model(const std::string& dir, const std::string& name) {
  std::string text = read_text(source_dir() + "/config/robots/docent.yaml");
  const auto at = text.find("name: docent");
  text.replace(at, std::string("name: docent").size(), "name: " + name);
  std::string path = dir + "/" + name + ".yaml";
  std::ofstream(path) << text;
  return path;
}

std::string daemon_yaml(const DaemonSetup& s, const std::string& model_path) {
  std::ostringstream y;
  y << "loop: {rate_hz: " << s.rate_hz << ", realtime: false}\n"
    << "robot_model: " << model_path << "\n"
    << "hardware: {plugin: sim, params: {seed: 3}}\n"
    << "drivetrain: {plugin: differential}\n"
    << "localization:\n  plugin: " << s.localization << "\n  params: " << s.localization_params
    << "\n"
    << "command:\n  timeout_s: 0.5\n  source: " << s.command_source << "\n";
  if (s.command_source == "script") {
    y << "  script:\n    - {vx_mps: " << s.script_vx_mps << ", wz_radps: " << s.script_wz_radps
      << ", duration_s: 100}\n";
  }
  y << "status: {period_s: 1.0}\n"
    << "dds:\n  domain_id: " << s.domain << "\n  config: " << source_dir()
    << "/config/dds/loopback.xml\n";
  return y.str();
}

// One daemon on its own configuration file in its own directory.
class DaemonUnderTest {
 public:
  DaemonUnderTest(const DaemonUnderTest&) = delete;
  DaemonUnderTest& operator=(const DaemonUnderTest&) = delete;
  DaemonUnderTest(DaemonUnderTest&&) = delete;
  DaemonUnderTest& operator=(DaemonUnderTest&&) = delete;
  DaemonUnderTest(const std::string& test, const DaemonSetup& setup,
                  const std::vector<std::pair<std::string, std::string>>& env = {},
                  std::vector<std::string> extra_args = {})
      : setup_(setup), dir_(make_test_dir(test)) {
    model_ = robot_model(dir_, setup.robot);
    config_ = dir_ + "/swiveld.yaml";
    std::ofstream(config_) << daemon_yaml(setup, model_);
    std::vector<std::string> args{"--config", config_};
    for (auto& a : extra_args) args.push_back(std::move(a));
    child_ = std::make_unique<Child>(swiveld_exe(), args, env);
  }
  ~DaemonUnderTest() {
    child_.reset();
    std::filesystem::remove_all(dir_);
  }

  void rewrite(const DaemonSetup& setup) { write_by_rename(config_, daemon_yaml(setup, model_)); }
  void rewrite_text(const std::string& text) { write_by_rename(config_, text); }

  [[nodiscard]] std::vector<std::string> ctl(std::vector<std::string> args) const {
    args.emplace_back("--domain");
    args.push_back(std::to_string(setup_.domain));
    args.emplace_back("--timeout");
    args.emplace_back("10");
    return args;
  }
  [[nodiscard]] std::vector<std::string> ctl_robot(std::vector<std::string> args) const {
    args.emplace_back("--robot");
    args.push_back(setup_.robot);
    return ctl(std::move(args));
  }

  /// The next `count` RobotState samples as JSON.
  [[nodiscard]] std::vector<json> states(int count) const {
    const ToolRun run =
        swivelctl(ctl_robot({"echo", "state", "--json", "--count", std::to_string(count)}));
    EXPECT_EQ(run.exit_code, 0) << run.err;
    std::vector<json> samples;
    for (const auto& line : lines_of(run.out)) samples.push_back(json::parse(line));
    return samples;
  }
  [[nodiscard]] json state() const {
    auto s = states(1);
    return s.empty() ? json{} : s.front();
  }
  [[nodiscard]] json diagnostics() const {
    const ToolRun run = swivelctl(ctl_robot({"echo", "diagnostics", "--json", "--count", "1"}));
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return run.out.empty() ? json{} : json::parse(lines_of(run.out).front());
  }

  Child& process() { return *child_; }
  [[nodiscard]] const std::string& dir() const { return dir_; }
  [[nodiscard]] const std::string& config() const { return config_; }
  [[nodiscard]] const std::string& model() const { return model_; }

 private:
  DaemonSetup setup_;
  std::string dir_;
  std::string model_;
  std::string config_;
  std::unique_ptr<Child> child_;
};

double x_of(const json& s) { return s["pose"]["x_m"].get<double>(); }
double y_of(const json& s) { return s["pose"]["y_m"].get<double>(); }

TEST(SwiveldDds, EchoShowsThePoseAndDriveMovesTheRobot) {
  DaemonSetup setup;
  setup.robot = "it_drive";
  setup.domain = 41;
  DaemonUnderTest daemon("drive", setup);

  const ToolRun echo = swivelctl(daemon.ctl_robot({"echo", "state", "--count", "5"}));
  ASSERT_EQ(echo.exit_code, 0) << echo.err << daemon.process().err();
  const auto lines = lines_of(echo.out);
  ASSERT_EQ(lines.size(), 5U) << echo.out;
  EXPECT_NE(lines[0].find("it_drive"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("x="), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("localization=raw_eg"), std::string::npos) << lines[0];
  const double x0 = x_of(daemon.state());

  const ToolRun drive = swivelctl(daemon.ctl_robot({"drive", "0.3", "0", "0", "--for", "2"}));
  ASSERT_EQ(drive.exit_code, 0) << drive.err;

  // About 0.6 m forward; the robot accelerates within its wheel-rate limit.
  const json after = daemon.state();
  EXPECT_GT(x_of(after) - x0, 0.3);
  EXPECT_LT(x_of(after) - x0, 0.9);
  EXPECT_NEAR(y_of(after), 0.0, 0.05);
  EXPECT_TRUE(daemon.process().alive());

  // Each state carries its stamp twice: CLOCK_MONOTONIC and ROS time, which agree through
  // the offset of the two clocks (measured here the way any program on this host would).
  // Pose and twist come with their covariances.
  timespec mono{};
  timespec real{};
  clock_gettime(CLOCK_MONOTONIC, &mono);
  clock_gettime(CLOCK_REALTIME, &real);
  const double offset_s = static_cast<double>(real.tv_sec - mono.tv_sec) +
                          1e-9 * static_cast<double>(real.tv_nsec - mono.tv_nsec);
  for (const json& s : daemon.states(10)) {
    const double ros_s =
        s["ros_stamp"]["sec"].get<double>() + 1e-9 * s["ros_stamp"]["nanosec"].get<double>();
    EXPECT_NEAR(ros_s - s["stamp_s"].get<double>(), offset_s, 1e-3) << s.dump();
    EXPECT_TRUE(s["has_covariance"].get<bool>());
    EXPECT_GT(s["pose_covariance"][0].get<double>(), 0.0);
    EXPECT_TRUE(s["has_twist_covariance"].get<bool>());
  }
}

TEST(SwiveldDds, RobotStopsOnCommandTimeoutWhenTheCommandSourceIsKilled) {
  DaemonSetup setup;
  setup.robot = "it_timeout";
  setup.domain = 42;
  DaemonUnderTest daemon("timeout", setup);
  ASSERT_EQ(daemon.states(1).size(), 1U) << daemon.process().err();

  Child drive(swivelctl_exe(), daemon.ctl_robot({"drive", "0.3", "0", "0"}));
  const auto deadline = Clock::now() + Seconds(10);
  json s;
  while (Clock::now() < deadline) {
    s = daemon.state();
    if (s.value("mode", "") == "velocity" && x_of(s) > 0.1) break;
  }
  ASSERT_EQ(s.value("mode", ""), "velocity") << s.dump();

  drive.signal(SIGKILL);  // no final zero command: only the timeout can stop the robot
  drive.wait_for(Seconds(5));
  std::this_thread::sleep_for(Seconds(1.5));  // timeout 0.5 s plus the stopping distance

  const json a = daemon.state();
  std::this_thread::sleep_for(Seconds(0.5));
  const json b = daemon.state();
  EXPECT_EQ(b["fault"], "command_timeout") << b.dump();
  EXPECT_EQ(b["command"]["vx_mps"].get<double>(), 0.0);
  EXPECT_NEAR(x_of(b), x_of(a), 1e-3) << "the robot still moves";
  EXPECT_TRUE(daemon.process().alive());
}

TEST(SwiveldDds, EditingTheConfigurationSwapsLocalizationWithoutGapOrJump) {
  DaemonSetup setup;
  setup.robot = "it_swap";
  setup.domain = 43;
  setup.rate_hz = 200.0;
  setup.command_source = "script";
  setup.script_vx_mps = 0.3;
  setup.script_wz_radps = 0.2;
  DaemonUnderTest daemon("swap", setup);
  ASSERT_EQ(daemon.states(1).size(), 1U) << daemon.process().err();

  Child stream(swivelctl_exe(), daemon.ctl_robot({"echo", "state", "--json"}));
  // What the swap costs the loop in time is measured by `swivel-bench swap`; this test
  // checks what a client sees: no gap, no jump, the new plugin named in the stream.
  std::this_thread::sleep_for(Seconds(1));  // the stream shows raw_eg before the swap
  DaemonSetup kalman = setup;
  kalman.localization = "kalman";
  kalman.localization_params = "{mode: ekf}";
  daemon.rewrite(kalman);  // a new file renamed over the old one, as editors save
  ASSERT_TRUE(daemon.process().wait_for_err("applied localization raw_eg -> kalman", Seconds(10)))
      << daemon.process().err();
  std::this_thread::sleep_for(Seconds(2));
  const json diagnostics = daemon.diagnostics();
  stream.signal(SIGINT);
  stream.wait_for(Seconds(5));

  std::vector<json> samples;
  for (const auto& line : lines_of(stream.out())) samples.push_back(json::parse(line));
  ASSERT_GT(samples.size(), 100U);
  const double period_s = 1.0 / setup.rate_hz;
  std::size_t first_kalman = 0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    const json& a = samples[i - 1];
    const json& b = samples[i];
    const auto dc = b["cycle"].get<std::uint64_t>() - a["cycle"].get<std::uint64_t>();
    const double dt = b["stamp_s"].get<double>() - a["stamp_s"].get<double>();
    ASSERT_GT(dc, 0U) << "cycles go backwards at sample " << i;
    // Stamps (wake-up times) advance by the cycles in between, less at most the first
    // sample's lateness (under a period: a later wake-up skips the deadlines it missed).
    EXPECT_GE(dt, static_cast<double>(dc - 1) * period_s) << "at sample " << i;
    // No hole in the stream (generous: a quarter second).
    EXPECT_LT(dt, 0.25) << "gap in the state stream at sample " << i;
    // No pose jump: at most the distance driven plus noise.
    const double step = std::hypot(x_of(b) - x_of(a), y_of(b) - y_of(a));
    EXPECT_LT(step, 0.3 * dt + 0.01)
        << "pose jump at sample " << i << ": " << a.dump() << " -> " << b.dump();
    if (first_kalman == 0 && b["localization_plugin"] == "kalman") {
      first_kalman = i;
      EXPECT_EQ(a["localization_plugin"], "raw_eg");
      EXPECT_EQ(b["localization_swaps"].get<int>(), a["localization_swaps"].get<int>() + 1);
    }
  }
  ASSERT_GT(first_kalman, 0U) << "the active plugin never changed in the stream";
  EXPECT_EQ(samples.back()["localization_plugin"], "kalman");

  EXPECT_EQ(diagnostics["plugins"]["localization"], "kalman");
  EXPECT_TRUE(diagnostics["last_reload_ok"].get<bool>());
}

TEST(SwiveldDds, BrokenConfigurationIsRejectedAndTheDaemonKeepsRunning) {
  DaemonSetup setup;
  setup.robot = "it_broken";
  setup.domain = 44;
  DaemonUnderTest daemon("broken", setup);
  ASSERT_EQ(daemon.states(1).size(), 1U) << daemon.process().err();

  // A misspelt key in the new localization's params.
  DaemonSetup broken = setup;
  broken.localization = "kalman";
  broken.localization_params = "{heading_sorce: gyro}";
  daemon.rewrite(broken);
  ASSERT_TRUE(daemon.process().wait_for_err("configuration rejected", Seconds(10)))
      << daemon.process().err();
  const std::string log = daemon.process().err();
  EXPECT_NE(log.find("swiveld.yaml:"), std::string::npos) << log;
  EXPECT_NE(log.find("heading_sorce"), std::string::npos) << log;

  const ToolRun reload = swivelctl(daemon.ctl_robot({"reload"}));
  EXPECT_EQ(reload.exit_code, 1) << reload.out << reload.err;
  EXPECT_NE(reload.out.find("rejected"), std::string::npos) << reload.out;
  EXPECT_NE(reload.out.find("heading_sorce"), std::string::npos) << reload.out;

  // Not YAML at all.
  daemon.rewrite_text("loop: {rate_hz: 200\nhardware: [\n");
  const ToolRun reload2 = swivelctl(daemon.ctl_robot({"reload"}));
  EXPECT_EQ(reload2.exit_code, 1) << reload2.out << reload2.err;
  EXPECT_NE(reload2.out.find("invalid YAML"), std::string::npos) << reload2.out;

  const json d = daemon.diagnostics();
  EXPECT_FALSE(d["last_reload_ok"].get<bool>());
  EXPECT_GE(d["reload_count"].get<int>(), 2);
  EXPECT_EQ(daemon.state()["localization_plugin"], "raw_eg");
  EXPECT_TRUE(daemon.process().alive());

  // A restart-only change is applied where it can be and reported.
  DaemonSetup faster = setup;
  faster.rate_hz = 1000.0;
  daemon.rewrite(faster);
  const ToolRun reload3 = swivelctl(daemon.ctl_robot({"reload"}));
  EXPECT_EQ(reload3.exit_code, 0) << reload3.out << reload3.err;
  EXPECT_NE(reload3.out.find("needs a restart: loop.rate_hz"), std::string::npos) << reload3.out;
}

TEST(SwiveldDds, ThreeDaemonsOnOneDomainAreAllVisibleToStatus) {
  std::vector<std::unique_ptr<DaemonUnderTest>> fleet;
  const std::vector<std::string> ids{"it_fleet_a", "it_fleet_b", "it_fleet_c"};
  for (const auto& id : ids) {
    DaemonSetup setup;
    setup.robot = id;
    setup.domain = 45;
    setup.rate_hz = 200.0;
    fleet.push_back(std::make_unique<DaemonUnderTest>(id, setup));
  }
  std::set<std::string> seen;
  for (int attempt = 0; attempt < 5 && seen.size() < ids.size(); ++attempt) {
    const ToolRun status = swivelctl({"status", "--json", "--domain", "45", "--timeout", "10"});
    if (status.exit_code != 0) continue;
    const json all = json::parse(lines_of(status.out).back());
    for (const auto& [id, summary] : all.items()) seen.insert(id);
  }
  for (const auto& id : ids) EXPECT_TRUE(seen.count(id)) << id << " missing from status";
  const ToolRun table = swivelctl({"status", "--domain", "45", "--timeout", "10"});
  for (const auto& id : ids) EXPECT_NE(table.out.find(id), std::string::npos) << table.out;
}

// Reads datagrams from a NOTIFY_SOCKET as systemd does.
class NotifySocket {
 public:
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;
  NotifySocket(NotifySocket&&) = delete;
  NotifySocket& operator=(NotifySocket&&) = delete;
  explicit NotifySocket(std::string path)
      : path_(std::move(path)), fd_(socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0)) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path_.c_str());
    std::remove(path_.c_str());
    if (bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
      ADD_FAILURE() << "cannot bind the notify socket " << path_;
    timeval tv{0, 100000};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~NotifySocket() {
    close(fd_);
    std::remove(path_.c_str());
  }
  /// Waits for a datagram containing `line` as one of its lines; false after `limit`.
  bool wait_for(const std::string& line, Seconds limit) {
    const auto deadline = Clock::now() + limit;
    while (Clock::now() < deadline) {
      char buffer[4096];
      const ssize_t n = recv(fd_, buffer, sizeof buffer, 0);
      if (n <= 0) continue;
      const std::string message(buffer, static_cast<std::size_t>(n));
      received_.push_back(message);
      for (const auto& l : lines_of(message)) {
        if (l == line) return true;
      }
    }
    return false;
  }
  [[nodiscard]] std::string received() const {
    std::string all;
    for (const auto& m : received_) all += "[" + m + "] ";
    return all;
  }

 private:
  std::string path_;
  int fd_ = -1;
  std::vector<std::string> received_;
};

TEST(SwiveldService, SpeaksTheSdNotifyProtocol) {
  const std::string dir = make_test_dir("notify");
  NotifySocket notify(dir + "/notify.sock");
  DaemonSetup setup;
  setup.robot = "it_notify";
  setup.domain = 46;
  DaemonUnderTest daemon("notify", setup,
                         {{"NOTIFY_SOCKET", dir + "/notify.sock"}, {"WATCHDOG_USEC", "400000"}});

  EXPECT_TRUE(notify.wait_for("READY=1", Seconds(10))) << notify.received();
  EXPECT_TRUE(notify.wait_for("WATCHDOG=1", Seconds(5))) << notify.received();
  EXPECT_TRUE(notify.wait_for("WATCHDOG=1", Seconds(5))) << "the watchdog is sent repeatedly";
  daemon.process().signal(SIGHUP);
  EXPECT_TRUE(notify.wait_for("RELOADING=1", Seconds(10))) << notify.received();
  EXPECT_TRUE(notify.wait_for("READY=1", Seconds(10))) << notify.received();
  daemon.process().signal(SIGTERM);
  EXPECT_TRUE(notify.wait_for("STOPPING=1", Seconds(10))) << notify.received();
  EXPECT_EQ(daemon.process().exit_code(Seconds(10)), 0) << daemon.process().err();
  std::filesystem::remove_all(dir);
}

TEST(SwiveldRecord, RecordsARunLogFromTheLiveRun) {
  const std::string dir = make_test_dir("record");
  const std::string log_path = dir + "/run.csv";
  DaemonSetup setup;
  setup.robot = "it_record";
  setup.domain = 47;
  setup.command_source = "script";
  setup.script_vx_mps = 0.2;
  DaemonUnderTest daemon("record", setup, {}, {"--record", log_path, "--record-rate-hz", "50"});
  ASSERT_EQ(daemon.states(1).size(), 1U) << daemon.process().err();
  std::this_thread::sleep_for(Seconds(2));
  daemon.process().signal(SIGTERM);
  ASSERT_EQ(daemon.process().exit_code(Seconds(10)), 0) << daemon.process().err();

  const RunLog log = read_run_log(log_path);
  EXPECT_EQ(log.header.robot, "it_record");
  EXPECT_EQ(log.header.drivetrain, DrivetrainKind::kDifferential);
  ASSERT_GT(log.samples.size(), 60U);  // 50 Hz for over 2 s
  const auto& first = log.samples.front();
  const auto& last = log.samples.back();
  const double rate = static_cast<double>(log.samples.size() - 1) / (last.t_s - first.t_s);
  EXPECT_NEAR(rate, 50.0, 10.0);
  EXPECT_GT(last.wheel_rad[0], first.wheel_rad[0] + 1.0);  // both wheels turned forward
  EXPECT_GT(last.wheel_rad[1], first.wheel_rad[1] + 1.0);
  EXPECT_TRUE(last.has_truth);
  EXPECT_GT(last.truth.x_m, 0.2);
  // The truth is the simulator's own, on the loop's clock at the robot's reference point: the
  // log says so, and the model-gap workflow fits no motion-capture clock or mounting for it.
  const auto& comments = log.header.comments;
  EXPECT_NE(std::find(comments.begin(), comments.end(), "truth_clock: shared"), comments.end());
  EXPECT_NE(std::find(comments.begin(), comments.end(), "truth_frame: robot"), comments.end());
  std::filesystem::remove_all(dir);
}

TEST(SwiveldSwpc4, ShippedConfigurationDrivesTheCasterRobotAsCommanded) {
  // The shipped file as is: domain 0, robot id swpc4 (tests filter on the id).
  Child daemon(swiveld_exe(), {"--config", source_dir() + "/config/swiveld_swpc4.yaml"});
  const ToolRun run = swivelctl(
      {"echo", "state", "--json", "--robot", "swpc4", "--count", "900", "--timeout", "10"},
      Seconds(40));
  ASSERT_EQ(run.exit_code, 0) << run.err << daemon.err();
  std::vector<json> samples;
  for (const auto& line : lines_of(run.out)) samples.push_back(json::parse(line));
  ASSERT_EQ(samples.size(), 900U);

  // Mean true velocity over each stretch that held one command, from 0.8 s into it (the
  // casters turn first) for at least one second.
  struct Stretch {
    double vx = 0, vy = 0, t_start = 0;
    std::optional<std::array<double, 3>> anchor;  // t, x, y
  };
  std::map<std::string, std::pair<double, double>> measured;  // command sign -> velocity
  std::optional<Stretch> current;
  for (const auto& s : samples) {
    const double vx = s["command"]["vx_mps"].get<double>();
    const double vy = s["command"]["vy_mps"].get<double>();
    const double t = s["stamp_s"].get<double>();
    const double x = s["truth"]["x_m"].get<double>();
    const double y = s["truth"]["y_m"].get<double>();
    if (!current || std::abs(current->vx - vx) > 1e-6 || std::abs(current->vy - vy) > 1e-6) {
      current = Stretch{vx, vy, t, std::nullopt};
      continue;
    }
    if (!current->anchor) {
      if (t - current->t_start >= 0.8) current->anchor = std::array<double, 3>{t, x, y};
      continue;
    }
    const auto& [ta, xa, ya] = *current->anchor;
    if (t - ta > 1.0) {
      const std::string key{vx > 0.1    ? '+'
                            : vx < -0.1 ? '-'
                                        : '0',
                            vy > 0.1    ? '+'
                            : vy < -0.1 ? '-'
                                        : '0'};
      measured[key] = {(x - xa) / (t - ta), (y - ya) / (t - ta)};
    }
  }
  ASSERT_TRUE(measured.count("+0")) << "no forward stretch seen";
  ASSERT_TRUE(measured.count("0+")) << "no leftward stretch seen";
  EXPECT_NEAR(measured["+0"].first, 0.2, 0.05);
  EXPECT_NEAR(measured["+0"].second, 0.0, 0.05);
  EXPECT_NEAR(measured["0+"].first, 0.0, 0.05);
  EXPECT_NEAR(measured["0+"].second, 0.2, 0.05);
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(Seconds(10)), 0) << daemon.err();
}

}  // namespace
}  // namespace swivel::test
