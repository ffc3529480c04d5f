// SPDX-License-Identifier: Apache-2.0
// How far the simulated robot travels once swiveld starts stopping it. swiveld runs the
// docent robot at 1 kHz and is driven at 0.5 m/s over DDS; a swivelctl stream records the
// state (cycle stamps and the simulator's true pose). After SIGTERM the loop logs the cycle
// time at which its controlled stop began; the test takes the true position at that instant
// from the last state before it (the robot moves at a steady speed there) and compares it
// with where the robot came to rest: at most v^2 / (2 a_max), plus one cycle's travel and
// one for the log's millisecond stamp. How long the daemon took to start stopping is a
// separate, generous bound: it depends on how loaded the machine is. The state keeps coming
// until the robot is at rest (DDS goes last), and the daemon logs that it deactivated the
// hardware after the robot stopped.

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "process_util.hpp"
#include "swivel/clock.hpp"

namespace swivel::test {
namespace {

using nlohmann::json;

constexpr double kSpeedMps = 0.5;
constexpr double kRateHz = 1000.0;

struct StopRun {
  double distance_m = 0.0;  ///< travelled from the start of the controlled stop
  double speed_mps = 0.0;   ///< measured just before it
  double reaction_s = 0.0;  ///< from SIGTERM to the start of the controlled stop
  int exit_code = -1;
  std::string log;
};

// The docent model under `robot`, with `limits` (a YAML mapping or "") added.
StopRun stop_after_sigterm(const std::string& robot, int domain, const std::string& limits,
                           const std::string& controlled_stop) {
  const std::string dir = make_test_dir("stop_" + robot);
  std::string model = read_text(source_dir() + "/config/robots/docent.yaml");
  model.replace(model.find("name: docent"), std::string("name: docent").size(), "name: " + robot);
  if (!limits.empty()) model += "limits: " + limits + "\n";
  std::ofstream(dir + "/robot.yaml") << model;
  std::ofstream(dir + "/swiveld.yaml")
      << "loop: {rate_hz: " << kRateHz << ", realtime: false}\n"
      << "robot_model: robot.yaml\n"
      << "hardware: {plugin: sim, params: {seed: 3}}\n"
      << "drivetrain: {plugin: differential}\n"
      << "localization: {plugin: raw_eg}\n"
      << "command: {timeout_s: 0.5, source: none}\n"
      << "controlled_stop: " << controlled_stop << "\n"
      << "dds:\n  domain_id: " << domain << "\n  config: " << source_dir()
      << "/config/dds/loopback.xml\n";
  const std::vector<std::string> ctl_tail = {"--robot",   robot, "--domain", std::to_string(domain),
                                             "--timeout", "10"};
  auto ctl = [&](std::vector<std::string> args) {
    args.insert(args.end(), ctl_tail.begin(), ctl_tail.end());
    return args;
  };

  StopRun run;
  Child daemon(swiveld_exe(), {"--config", dir + "/swiveld.yaml"});
  Child stream(swivelctl_exe(), ctl({"echo", "state", "--json"}));
  Child drive(swivelctl_exe(), ctl({"drive", std::to_string(kSpeedMps), "0", "0"}));
  // At speed for a while: the stop then starts from a steady 0.5 m/s.
  const auto deadline = Clock::now() + Seconds(20);
  bool steady = false;
  while (!steady && Clock::now() < deadline && daemon.alive()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const auto lines = lines_of(stream.out());
    int at_speed = 0;
    for (auto it = lines.rbegin(); it != lines.rend() && at_speed < 50; ++it) {
      const json s = json::parse(*it, nullptr, false);
      if (s.is_discarded() || std::abs(s["command"]["vx_mps"].get<double>() - kSpeedMps) > 1e-9) {
        break;
      }
      ++at_speed;
    }
    steady = at_speed >= 50;  // half a second of samples
  }
  if (!steady) {
    ADD_FAILURE() << "the robot never drove at " << kSpeedMps << " m/s\n" << daemon.err();
    return run;
  }

  const double sigterm_s = monotonic_s();
  daemon.signal(SIGTERM);
  run.exit_code = daemon.exit_code(Seconds(20));
  drive.signal(SIGKILL);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  stream.signal(SIGINT);
  stream.wait_for(Seconds(5));
  run.log = daemon.err();

  std::vector<json> states;
  for (const auto& line : lines_of(stream.out())) {
    json s = json::parse(line, nullptr, false);
    if (!s.is_discarded() && s.contains("truth")) states.push_back(std::move(s));
  }
  // "loop cycle N t=12.345s: message: controlled stop: commands ignored, ...": the loop's
  // clock, the clock of the states' stamps.
  const std::size_t stop_line = run.log.find("controlled stop: commands ignored");
  const std::size_t stamp = run.log.rfind(" t=", stop_line);
  if (stop_line == std::string::npos || stamp == std::string::npos) {
    ADD_FAILURE() << "the loop never logged the start of its controlled stop\n" << run.log;
    return run;
  }
  const double stop_s = std::stod(run.log.substr(stamp + 3));
  run.reaction_s = stop_s - sigterm_s;
  std::size_t last_before = 0;
  while (last_before + 1 < states.size() && states[last_before + 1]["stamp_s"] <= stop_s) {
    ++last_before;
  }
  if (states.size() < 50 || last_before < 20 || last_before + 1 >= states.size()) {
    ADD_FAILURE() << "too few states around SIGTERM (" << states.size() << ")";
    return run;
  }
  const auto x = [](const json& s) { return s["truth"]["x_m"].get<double>(); };
  const auto t = [](const json& s) { return s["stamp_s"].get<double>(); };
  const json& before = states[last_before];
  const json& earlier = states[last_before - 20];
  run.speed_mps = (x(before) - x(earlier)) / (t(before) - t(earlier));
  const double at_stop_m = x(before) + run.speed_mps * (stop_s - t(before));
  run.distance_m = x(states.back()) - at_stop_m;
  // The stream went on until the robot was at rest.
  EXPECT_EQ(states.back()["command"]["vx_mps"].get<double>(), 0.0);
  EXPECT_LT(std::abs(states.back()["twist"]["vx_mps"].get<double>()), 0.005);
  std::filesystem::remove_all(dir);
  return run;
}

void expect_stop_within(const StopRun& run, double a_max_mps2) {
  EXPECT_EQ(run.exit_code, 0) << run.log;
  EXPECT_NEAR(run.speed_mps, kSpeedMps, 0.005);
  // The loop stamps a cycle with its scheduled start: a cycle that woke late can take a SIGTERM
  // sent after its stamp (seen: 9 us), so the reaction may read up to one period negative.
  EXPECT_GE(run.reaction_s, -1.0 / kRateHz) << run.log;
  EXPECT_LT(run.reaction_s, 0.1) << "SIGTERM took long to start the stop\n" << run.log;
  const double bound_m = kSpeedMps * kSpeedMps / (2.0 * a_max_mps2) + 2.0 * kSpeedMps / kRateHz;
  EXPECT_LE(run.distance_m, bound_m) << run.log;
  // And not a stop harder than the limit allows (a margin for the sampling).
  EXPECT_GE(run.distance_m, kSpeedMps * kSpeedMps / (2.0 * a_max_mps2) - 0.002);
  std::printf(
      "stop began %.1f ms after SIGTERM; travelled %.5f m from %.4f m/s at %.1f m/s^2 (bound "
      "%.5f m)\n",
      run.reaction_s * 1e3, run.distance_m, run.speed_mps, a_max_mps2, bound_m);
  // Stop first: the robot at rest, then the drives off, then everything else.
  const auto rest = run.log.find("robot at rest after");
  const auto deactivated = run.log.find("hardware sim deactivated");
  ASSERT_NE(rest, std::string::npos) << run.log;
  ASSERT_NE(deactivated, std::string::npos) << run.log;
  EXPECT_LT(rest, deactivated);
  EXPECT_NE(run.log.find("stopped cleanly"), std::string::npos) << run.log;
}

TEST(SwiveldStop, SigtermStopsWithinTheRobotModelsDeceleration) {
  const StopRun run = stop_after_sigterm("it_stop_model", 71, "{linear_acceleration_mps2: 1.0}",
                                         "{linear_deceleration_mps2: 3.0}");
  expect_stop_within(run, 1.0);
}

TEST(SwiveldStop, WithoutModelLimitsSigtermStopsAtTheConfiguredDeceleration) {
  const StopRun run =
      stop_after_sigterm("it_stop_default", 72, "", "{linear_deceleration_mps2: 2.0}");
  expect_stop_within(run, 2.0);
}

}  // namespace
}  // namespace swivel::test
