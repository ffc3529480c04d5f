// SPDX-License-Identifier: Apache-2.0
// The real plugins (sim, the robot's drivetrain, raw_eg, then kalman and lsm swapped in),
// loaded through PluginLoader as the daemon loads them, on a ControlLoop driven by
// run_cycle() on a dedicated thread, for both robots (docent: differential; swpc4: four
// powered casters): over more than 10,000 cycles with three hot swaps and a robot-model swap
// (a new drivetrain and localization, taken with the robot at rest), that thread makes no
// heap allocation, and the pose stays continuous across each swap.

#include <gtest/gtest.h>
#include <time.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "alloc_guard.hpp"
#include "swivel/plugin_loader.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::test {
namespace {

constexpr double kRateHz = 1000.0;
constexpr double kSpeedMps = 0.3;
constexpr std::uint64_t kCycles = 14000;
// The new model's speed limit, below the commanded kSpeedMps: its effect is measurable.
constexpr double kNewModelSpeedLimitMps = 0.2;
constexpr std::uint64_t kWarmUpCycles = 200;

std::string source_dir() {
  const char* dir = std::getenv("SWIVEL_SOURCE_DIR");
  return dir != nullptr ? dir : ".";
}

template <class Interface>
PluginInstance<Interface> make(PluginLoader& loader, const std::string& name,
                               const std::string& params_yaml, const RobotModel& robot) {
  PluginInstance<Interface> plugin = loader.create<Interface>(name);
  PluginContext ctx;
  ctx.params = YAML::Load(params_yaml);
  ctx.config_file = "hot_swap_alloc_test";
  ctx.params_path = name + ".params";
  ctx.config_dir = source_dir() + "/config";
  ctx.robot = &robot;
  ctx.period_s = 1.0 / kRateHz;
  plugin->configure(ctx);
  return plugin;
}

struct Robot {
  const char* model;       // config/robots/<model>.yaml
  const char* drivetrain;  // its drivetrain plugin
};

class HotSwapAllocation : public ::testing::TestWithParam<Robot> {};

TEST_P(HotSwapAllocation, RealPluginsSwapWithoutAllocationOnTheLoopThread) {
  const RobotModel robot =
      load_robot_model(source_dir() + "/config/robots/" + GetParam().model + ".yaml");
  PluginLoader loader(PluginLoader::default_search_path());
  auto hardware = make<Hardware>(loader, "sim", "{seed: 7}", robot);
  auto drivetrain = make<Drivetrain>(loader, GetParam().drivetrain, "{}", robot);
  auto localization = make<Localization>(loader, "raw_eg", "{heading_source: gyro}", robot);
  localization->reset(PoseEstimate{});

  rt::LoopOptions options;
  options.rate_hz = kRateHz;
  options.realtime = false;
  rt::ControlLoop loop(options, *hardware, *drivetrain, *localization, "raw_eg");

  std::atomic<bool> swaps_done{false};
  std::atomic<bool> hold_still{false};  // the swapping thread wants the robot at rest
  double fastest_after_model_swap_mps = 0.0;
  HeapCounts counts;
  double max_step_m = 0.0;
  std::uint64_t cycles_armed = 0;
  std::thread loop_thread([&] {
    double t = loop.now_s();
    const double dt = 1.0 / kRateHz;
    std::uint64_t sequence = 0;
    // This thread is the command source too (single producer), on the loop's synthetic time.
    auto cycle = [&] {
      VelocityCommand command;
      const bool still = hold_still.load(std::memory_order_acquire);
      command.twist.vx_mps = still ? 0.0 : kSpeedMps;
      command.twist.wz_radps = still ? 0.0 : 0.1;
      command.received_s = t;
      command.sequence = ++sequence;
      loop.push_command(command);
      loop.run_cycle(t);
      t += dt;
    };
    for (std::uint64_t i = 0; i < kWarmUpCycles; ++i) cycle();
    Pose2 previous = loop.latest().estimate.pose;
    std::uint64_t swaps_seen = loop.latest().localization_swaps;
    AllocCounter counter;
    std::uint64_t i = 0;
    // Paced a little so that the swapping thread's requests land among the cycles.
    const timespec pause{0, 50'000};
    while (i < kCycles || !swaps_done.load(std::memory_order_acquire)) {
      cycle();
      const StateSnapshot s = loop.latest();
      const Pose2& pose = s.estimate.pose;
      // The step across each swap: the outgoing estimate handed over, one cycle driven.
      if (s.localization_swaps != swaps_seen) {
        max_step_m =
            std::max(max_step_m, std::hypot(pose.x_m - previous.x_m, pose.y_m - previous.y_m));
        swaps_seen = s.localization_swaps;
      }
      if (s.model_swaps > 0) {
        fastest_after_model_swap_mps =
            std::max(fastest_after_model_swap_mps, std::abs(s.command_twist.vx_mps));
      }
      previous = pose;
      ++i;
      clock_nanosleep(CLOCK_MONOTONIC, 0, &pause, nullptr);
    }
    counts = counter.counts();
    cycles_armed = i;
  });

  // The swapping thread: build, configure and reset each new instance off the loop, request
  // the swap, then destroy the retired instance once the loop let go of it.
  const struct {
    const char* name;
    const char* params;
    std::uint64_t at_cycle;
  } swaps[] = {{"kalman", "{mode: ekf}", 3000},
               {"lsm", "{mode: heading_aligned}", 6000},
               {"raw_eg", "{heading_source: encoders}", 9000}};
  for (const auto& swap : swaps) {
    while (loop.latest().cycle < kWarmUpCycles + swap.at_cycle) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    auto next = make<Localization>(loader, swap.name, swap.params, robot);
    next->reset(loop.latest().estimate);
    const std::uint64_t swaps_before = loop.latest().localization_swaps;
    ASSERT_TRUE(loop.request_localization_swap(next.get(), swap.name));
    // Taken (swap_pending() false) happens at the start of a cycle; the snapshot naming the
    // new plugin is published at its end.
    while (loop.swap_pending() || loop.latest().localization_swaps == swaps_before) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    Localization* retired = loop.take_retired_localization();
    ASSERT_EQ(retired, localization.get());
    localization = std::move(next);  // destroys the retired instance here, off the loop
    EXPECT_STREQ(loop.latest().localization_plugin.data(), swap.name);
  }

  // A new robot model (the same geometry with a speed limit): a drivetrain and a
  // localization built for it off the loop, taken together at a cycle where the robot is at
  // rest, the outgoing pair destroyed here.
  RobotModel limited = robot;
  limited.limits.linear_velocity_mps = kNewModelSpeedLimitMps;
  while (loop.latest().cycle < kWarmUpCycles + 10000) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  rt::LoopSwap model_swap;
  auto next_drivetrain = make<Drivetrain>(loader, GetParam().drivetrain, "{}", limited);
  auto next_localization =
      make<Localization>(loader, "raw_eg", "{heading_source: encoders}", limited);
  next_localization->reset(loop.latest().estimate);
  model_swap.localization = next_localization.get();
  rt::copy_text("raw_eg", model_swap.localization_name);
  model_swap.drivetrain = next_drivetrain.get();
  model_swap.model = rt::model_settings(limited);
  ASSERT_TRUE(loop.request_swap(&model_swap));
  // Not taken while the robot drives.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_TRUE(loop.swap_pending());
  EXPECT_EQ(loop.latest().model_swaps, 0U);
  hold_still.store(true, std::memory_order_release);
  rt::LoopSwap* retired = loop.take_retired_swap();
  for (int i = 0; i < 10000 && retired == nullptr; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    retired = loop.take_retired_swap();
  }
  ASSERT_EQ(retired, &model_swap) << "the loop never took the model swap at rest";
  EXPECT_TRUE(model_swap.outcome.taken) << model_swap.outcome.refusal.data();
  EXPECT_EQ(model_swap.drivetrain, drivetrain.get());  // the outgoing pair came back
  EXPECT_EQ(model_swap.localization, localization.get());
  drivetrain = std::move(next_drivetrain);  // destroys the outgoing instances off the loop
  localization = std::move(next_localization);
  hold_still.store(false, std::memory_order_release);
  // Driving again under the new model before the loop thread may end.
  while (loop.latest().model_swaps == 0 || loop.latest().command_twist.vx_mps == 0.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  swaps_done.store(true, std::memory_order_release);
  loop_thread.join();

  EXPECT_GE(cycles_armed, kCycles);
  EXPECT_EQ(counts.allocations, 0U)
      << "first allocation: " << counts.first_allocation_bytes << " bytes";
  EXPECT_EQ(counts.deallocations, 0U);
  const StateSnapshot last = loop.latest();
  EXPECT_EQ(last.localization_swaps, 4U);
  EXPECT_EQ(last.model_swaps, 1U);
  // The new model's limits apply: the 0.3 m/s command is held at its speed limit.
  EXPECT_NEAR(fastest_after_model_swap_mps, kNewModelSpeedLimitMps, 1e-9);
  EXPECT_EQ(last.fault, FaultCode::kNone) << fault_code_name(last.fault);
  // Continuous pose across the swaps: no step larger than one cycle's travel plus noise.
  EXPECT_LT(max_step_m, kSpeedMps / kRateHz + 1e-3);
  EXPECT_GT(last.estimate.pose.x_m, 0.5);  // it did drive
  // Every plugin tracked the (nominal = true) robot: raw_eg on encoders at the end.
  EXPECT_LT(
      std::hypot(last.estimate.pose.x_m - last.truth.x_m, last.estimate.pose.y_m - last.truth.y_m),
      0.05);
}

INSTANTIATE_TEST_SUITE_P(BothRobots, HotSwapAllocation,
                         ::testing::Values(Robot{"docent", "differential"}, Robot{"swpc4", "swpc"}),
                         [](const ::testing::TestParamInfo<Robot>& robot) {
                           return std::string(robot.param.model);
                         });

}  // namespace
}  // namespace swivel::test
