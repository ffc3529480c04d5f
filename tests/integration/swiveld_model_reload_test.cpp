// SPDX-License-Identifier: Apache-2.0
// A new robot model applied to a running swiveld by a reload (docs/lab.md "The loop on a
// live robot"): the drivetrain and the localization are rebuilt for it and taken by the loop
// with the robot at rest; a reload while it moves is refused with the rule; a model the
// running robot cannot take is rejected and the daemon keeps its model. Real processes over
// loopback DDS, domains 91 and 92.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "process_util.hpp"

namespace swivel::test {
namespace {

using nlohmann::json;

// The sim keeps the wheels it was built with (0.075 m); the edited model says 0.09 m.
constexpr double kTrueRadiusM = 0.075;
constexpr double kEditedRadiusM = 0.09;
constexpr double kDriveMps = 0.2;

// `model` (a file under config/robots/) under the robot id `robot`, in `dir`.
std::string write_model(const std::string& dir, const std::string& model,
                        const std::string& robot) {
  std::string text = read_text(source_dir() + "/config/robots/" + model + ".yaml");
  const std::string name = "name: " + model;
  text.replace(text.find(name), name.size(), "name: " + robot);
  std::string path = dir + "/" + robot + ".yaml";
  std::ofstream(path) << text;
  return path;
}

std::string write_config(const std::string& dir, const std::string& model_path, int domain,
                         const std::string& drivetrain) {
  std::ofstream config(dir + "/swiveld.yaml");
  config << "loop: {rate_hz: 500, realtime: false}\n"
         << "robot_model: " << model_path << "\n"
         << "hardware: {plugin: sim, params: {seed: 9}}\n"
         << "drivetrain: {plugin: " << drivetrain << "}\n"
         << "localization: {plugin: raw_eg, params: {heading_source: gyro}}\n"
         << "command: {timeout_s: 0.5, source: none}\n"
         << "status: {period_s: 1.0}\n"
         << "dds:\n  domain_id: " << domain << "\n  config: " << source_dir()
         << "/config/dds/loopback.xml\n";
  return dir + "/swiveld.yaml";
}

// `text` with every `from` replaced by `to`.
std::string replaced_all(std::string text, const std::string& from, const std::string& to) {
  for (auto at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

class Robot {
 public:
  Robot(std::string id, int domain) : id_(std::move(id)), domain_(domain) {}

  [[nodiscard]] std::vector<std::string> ctl(std::vector<std::string> args) const {
    for (const std::string& a :
         {std::string("--domain"), std::to_string(domain_), std::string("--robot"), id_,
          std::string("--timeout"), std::string("10")}) {
      args.push_back(a);
    }
    return args;
  }
  [[nodiscard]] json state() const {
    const ToolRun run = swivelctl(ctl({"echo", "state", "--json", "--count", "1"}));
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return run.out.empty() ? json{} : json::parse(lines_of(run.out).front());
  }
  [[nodiscard]] json diagnostics() const {
    const ToolRun run = swivelctl(ctl({"echo", "diagnostics", "--json", "--count", "1"}));
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return run.out.empty() ? json{} : json::parse(lines_of(run.out).front());
  }
  [[nodiscard]] ToolRun reload() const { return swivelctl(ctl({"reload"})); }

  // Drives straight for `seconds` from rest and comes back to rest: the distance the
  // estimate moved over the distance the robot (the simulator's truth) moved.
  [[nodiscard]] double estimate_over_truth(double seconds) const {
    const json before = state();
    const ToolRun drive = swivelctl(
        ctl({"drive", std::to_string(kDriveMps), "0", "0", "--for", std::to_string(seconds)}),
        Seconds(seconds + 20));
    EXPECT_EQ(drive.exit_code, 0) << drive.err;
    std::this_thread::sleep_for(Seconds(0.5));  // at rest again
    const json after = state();
    const auto moved = [&](const char* key) {
      return std::hypot(after[key]["x_m"].get<double>() - before[key]["x_m"].get<double>(),
                        after[key]["y_m"].get<double>() - before[key]["y_m"].get<double>());
    };
    const double truth_m = moved("truth");
    EXPECT_GT(truth_m, 0.5 * kDriveMps * seconds) << "the robot did not drive";
    return moved("pose") / truth_m;
  }

 private:
  std::string id_;
  int domain_;
};

TEST(SwiveldModelReload, AnEditedModelAppliesAtRestAndTheOdometryUsesIt) {
  const std::string dir = make_test_dir("model_reload");
  const Robot robot("it_model", 91);
  const std::string model = write_model(dir, "docent", "it_model");
  Child daemon(swiveld_exe(), {"--config", write_config(dir, model, 91, "differential")});
  ASSERT_TRUE(robot.state().contains("pose")) << daemon.err();
  EXPECT_EQ(robot.diagnostics()["robot_model"], model);

  // The model the sim was built with: the estimate follows the truth.
  EXPECT_NEAR(robot.estimate_over_truth(2.0), 1.0, 0.03);

  // Edited in place (the file watcher watches swiveld.yaml only): larger wheels.
  const std::string original = read_text(model);
  const std::string edited = replaced_all(original, "_m: 0.075", "_m: 0.09");
  ASSERT_NE(edited, original);
  write_by_rename(model, edited);

  // While the robot drives, the model waits for rest and the reload gives up, saying why.
  Child drive(swivelctl_exe(), robot.ctl({"drive", std::to_string(kDriveMps), "0", "0"}));
  const auto deadline = Clock::now() + Seconds(10);
  while (Clock::now() < deadline && robot.state()["mode"] != "velocity") {
  }
  const ToolRun moving = robot.reload();
  EXPECT_EQ(moving.exit_code, 1) << moving.out << moving.err;
  EXPECT_NE(moving.out.find("robot_model: applies with the robot at rest"), std::string::npos)
      << moving.out;
  json d = robot.diagnostics();
  EXPECT_FALSE(d["last_reload_ok"].get<bool>());
  EXPECT_NE(d["last_reload_result"].get<std::string>().find("at rest"), std::string::npos)
      << d.dump();
  EXPECT_EQ(robot.state()["mode"], "velocity") << "the robot kept driving on its old model";
  drive.signal(SIGINT);  // sends a zero command as it ends
  ASSERT_EQ(drive.exit_code(Seconds(10)), 0) << drive.err();
  std::this_thread::sleep_for(Seconds(0.5));

  // At rest it applies, without a restart.
  const ToolRun at_rest = robot.reload();
  EXPECT_EQ(at_rest.exit_code, 0) << at_rest.out << at_rest.err << daemon.err();
  EXPECT_NE(at_rest.out.find("applied robot_model " + model), std::string::npos) << at_rest.out;
  EXPECT_EQ(at_rest.out.find("restart"), std::string::npos) << at_rest.out;
  d = robot.diagnostics();
  EXPECT_TRUE(d["last_reload_ok"].get<bool>()) << d.dump();
  EXPECT_EQ(d["robot_model"], model);
  // No latched fault (a command timeout since the drive ended is no fault of the swap).
  EXPECT_NE(robot.state()["mode"], "safe_stop");

  // The drivetrain drives the true 0.075 m wheels as if they were 0.09 m, and the odometry
  // integrates them as 0.09 m: the estimate now runs ahead of the truth by the ratio.
  EXPECT_NEAR(robot.estimate_over_truth(2.0), kEditedRadiusM / kTrueRadiusM, 0.03);

  // The loop of docs/lab.md: robot_model pointed at another file; the watcher reloads the edited
  // configuration and the diagnostics name the model in effect.
  const std::string augmented = dir + "/it_model.augmented.yaml";
  std::ofstream(augmented) << original;
  write_by_rename(dir + "/swiveld.yaml",
                  replaced_all(read_text(dir + "/swiveld.yaml"), model, augmented));
  ASSERT_TRUE(daemon.wait_for_err("robot model " + augmented, Seconds(10))) << daemon.err();
  EXPECT_EQ(robot.diagnostics()["robot_model"], augmented);
  EXPECT_NEAR(robot.estimate_over_truth(2.0), 1.0, 0.03);

  EXPECT_TRUE(daemon.alive());
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(Seconds(10)), 0) << daemon.err();
  std::filesystem::remove_all(dir);
}

TEST(SwiveldModelReload, AModelTheRobotCannotTakeIsRejectedAndTheDaemonKeepsItsModel) {
  const std::string dir = make_test_dir("model_reload_rejected");
  const Robot robot("it_model_swpc", 92);
  const std::string model = write_model(dir, "swpc4", "it_model_swpc");
  Child daemon(swiveld_exe(), {"--config", write_config(dir, model, 92, "swpc")});
  ASSERT_TRUE(robot.state().contains("pose")) << daemon.err();
  const std::string original = read_text(model);

  // Three modules for a robot whose hardware has four.
  const std::string last_module = "    - {x_m: -0.215, y_m: 0.125,";
  std::string three = original;
  const auto at = three.find(last_module);
  ASSERT_NE(at, std::string::npos);
  three.erase(at, three.find('\n', at) + 1 - at);
  write_by_rename(model, three);
  const ToolRun modules = robot.reload();
  EXPECT_EQ(modules.exit_code, 1) << modules.out << modules.err;
  EXPECT_NE(modules.out.find(model + ": 3 modules, but the running robot has 4"), std::string::npos)
      << modules.out;
  json d = robot.diagnostics();
  EXPECT_FALSE(d["last_reload_ok"].get<bool>());
  EXPECT_NE(d["last_reload_result"].get<std::string>().find("3 modules"), std::string::npos)
      << d.dump();

  // A value no drivetrain can take: named with its file.
  write_by_rename(model, replaced_all(original, "wheel_radius_m: 0.055", "wheel_radius_m: -0.055"));
  const ToolRun negative = robot.reload();
  EXPECT_EQ(negative.exit_code, 1) << negative.out << negative.err;
  EXPECT_NE(negative.out.find(model), std::string::npos) << negative.out;
  EXPECT_NE(negative.out.find("wheel_radius_m"), std::string::npos) << negative.out;

  // Not YAML at all.
  write_by_rename(model, "swpc: [\n");
  const ToolRun garbage = robot.reload();
  EXPECT_EQ(garbage.exit_code, 1) << garbage.out << garbage.err;
  EXPECT_NE(garbage.out.find(model), std::string::npos) << garbage.out;

  // Still running on its model, and it still drives.
  EXPECT_TRUE(daemon.alive()) << daemon.err();
  d = robot.diagnostics();
  EXPECT_EQ(d["robot_model"], model);
  // No latched fault (a command timeout since the drive ended is no fault of the swap).
  EXPECT_NE(robot.state()["mode"], "safe_stop");
  EXPECT_NEAR(robot.estimate_over_truth(1.5), 1.0, 0.05);
  write_by_rename(model, original);
  const ToolRun restored = robot.reload();
  EXPECT_EQ(restored.exit_code, 0) << restored.out << restored.err;
  EXPECT_NE(restored.out.find("no live change"), std::string::npos) << restored.out;

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.exit_code(Seconds(10)), 0) << daemon.err();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace swivel::test
