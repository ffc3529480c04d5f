// SPDX-License-Identifier: Apache-2.0
// Rows of docs/faults.md for plugins that fail on the loop (an error status, an exception)
// and plugin libraries that cannot be loaded when a hot swap is prepared.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "fault_rig.hpp"

namespace swivel::faults {
namespace {

constexpr double kVxMps = 0.3;

// Takes `next` in a hot swap at the next cycle and destroys the outgoing instance off the
// loop, as the daemon does.
void swap_to(FaultRig& rig, PluginInstance<Localization>& next, const char* name) {
  ASSERT_TRUE(rig.loop->request_localization_swap(next.get(), name));
  rig.step();
  ASSERT_EQ(rig.loop->take_retired_localization(), rig.localization.get());
  rig.localization = std::move(next);
}

// A localization that fails on the loop from its 301st update on: stop in that cycle, the
// cause in the log, no recovery while the plugin keeps failing (not even on request), and
// recovery once a working instance is swapped in and the fault cleared.
void run_failing_localization_row(const std::string& plugin, const std::string& params,
                                  const std::string& cause) {
  RigOptions options;
  options.localization = plugin;
  options.localization_params = params;
  FaultRig rig(options);
  // update() runs from the second cycle on (the first has no previous reading).
  rig.drive(kVxMps, 0.0, 0.0, 301);
  const StateSnapshot before = rig.state();
  ASSERT_EQ(before.mode, LoopMode::kVelocity);
  ASSERT_EQ(before.fault_count, 0U);

  rig.drive(kVxMps, 0.0, 0.0, 1);
  const StateSnapshot hit = rig.state();
  EXPECT_EQ(hit.cycle, before.cycle + 1);
  EXPECT_EQ(hit.mode, LoopMode::kSafeStop);
  EXPECT_EQ(hit.fault, FaultCode::kLocalizationError);
  EXPECT_EQ(hit.fault_count, 1U);
  EXPECT_EQ(max_wheel_setpoint(hit), 0.0);
  EXPECT_NE(rig.log().find("fault localization_error (#1): safe stop (" + cause + ")"),
            std::string::npos)
      << rig.log();

  rig.loop->clear_fault();  // the cause persists: the request waits
  rig.drive(kVxMps, 0.0, 0.0, 200);
  EXPECT_EQ(rig.state().cycle, hit.cycle + 200);
  EXPECT_EQ(rig.state().mode, LoopMode::kSafeStop);
  EXPECT_EQ(rig.state().fault_count, 1U);
  EXPECT_EQ(max_wheel_setpoint(rig.state()), 0.0);

  auto working = rig.make_localization("raw_eg", "{}");
  swap_to(rig, working, "raw_eg");  // the pending clear is honoured at this clean cycle
  EXPECT_EQ(rig.state().mode, LoopMode::kIdle);
  EXPECT_EQ(rig.state().fault, FaultCode::kNone);
  EXPECT_STREQ(rig.state().localization_plugin.data(), "raw_eg");
  rig.drive(kVxMps, 0.0, 0.0, 50);
  EXPECT_EQ(rig.state().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.state().fault_count, 1U);
}

TEST(PluginFaults, LocalizationReturningErrorStopsUntilReplaced) {
  run_failing_localization_row("update_error", "{fail_after_cycles: 300}",
                               "estimate diverged (planted failure)");
}

TEST(PluginFaults, LocalizationThrowingIsCaughtAtTheLoopBoundary) {
  run_failing_localization_row("throws_update", "{throw_after_cycles: 300}",
                               "plugin threw std::runtime_error: planted exception in update");
}

// A swap to a plugin whose hand_over() refuses (kError) or throws: the loop keeps the
// running instance, hands the refused one back with the reason, and raises no fault.
void run_refused_hand_over_row(const std::string& params, const std::string& reason) {
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 300);
  const StateSnapshot before = rig.state();
  auto refusing = rig.make_localization("refuses_hand_over", params);
  ASSERT_TRUE(rig.loop->request_localization_swap(refusing.get(), "refuses_hand_over"));
  rig.drive(kVxMps, 0.0, 0.0, 1);
  rt::SwapOutcome outcome;
  EXPECT_EQ(rig.loop->take_retired_localization(&outcome), refusing.get());
  EXPECT_FALSE(outcome.taken);
  EXPECT_STREQ(outcome.refusal.data(), reason.c_str());
  refusing.reset();  // off the loop, as the daemon does
  EXPECT_EQ(rig.loop->active_localization(), rig.localization.get());
  EXPECT_NE(rig.log().find("localization swap refused by the incoming plugin's hand-over (" +
                           reason + "); the active one stays"),
            std::string::npos)
      << rig.log();
  rig.drive(kVxMps, 0.0, 0.0, 100);
  const StateSnapshot after = rig.state();
  EXPECT_EQ(after.mode, LoopMode::kVelocity);
  EXPECT_EQ(after.fault_count, 0U);
  EXPECT_STREQ(after.localization_plugin.data(), "raw_eg");
  EXPECT_EQ(after.localization_swaps, before.localization_swaps);
  EXPECT_GT(after.estimate.pose.x_m, before.estimate.pose.x_m + kVxMps * 0.09);
}

TEST(PluginFaults, HandOverRefusedAtSwapTimeRollsBackWithoutAFault) {
  run_refused_hand_over_row("{}", "no map to place the pose in (planted refusal)");
}

TEST(PluginFaults, HandOverThrowingAtSwapTimeRollsBackWithoutAFault) {
  run_refused_hand_over_row("{throw: true}",
                            "plugin threw std::runtime_error: planted exception in hand_over");
}

// The PluginError message of `create`, or "no PluginError". (A test that FAILs inside a try
// returns there, as far as the static analyzer can tell: the values kept for after it would
// be dead stores.)
template <class Create>
std::string plugin_error_of(Create create) {
  try {
    create();
  } catch (const PluginError& e) {
    return e.what();
  }
  return "no PluginError";
}

// A swap prepared while the loop runs: the loader refuses, the loop never sees it.
void expect_loop_unaffected(FaultRig& rig, const StateSnapshot& before) {
  rig.drive(kVxMps, 0.0, 0.0, 100);
  const StateSnapshot after = rig.state();
  EXPECT_EQ(after.cycle, before.cycle + 100);
  EXPECT_EQ(after.mode, LoopMode::kVelocity);
  EXPECT_EQ(after.fault_count, 0U);
  EXPECT_EQ(after.localization_swaps, 0U);
  EXPECT_STREQ(after.localization_plugin.data(), "raw_eg");
  EXPECT_EQ(rig.loop->active_localization(), rig.localization.get());
  EXPECT_GT(distance_m(after.estimate.pose, before.estimate.pose), kVxMps * 0.09);
  EXPECT_LT(distance_m(after.estimate.pose, after.truth), 0.005);
}

TEST(PluginFaults, LibraryMissingAtSwapTimeLeavesTheRunningInstance) {
  // The running raw_eg came from a folder whose library file is then deleted (an upgrade
  // gone wrong): preparing a new instance fails, the mapped library keeps running.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "swivel_faults_missing_library";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  FaultRig rig;
  std::filesystem::copy_file(rig.localization.path(), dir / "swivel_localization_raw_eg.so");
  PluginLoader from_dir({dir.string()});
  auto running = from_dir.create<Localization>("raw_eg");
  running->configure(plugin_context("{}", "localization.params", rig.robot));
  running->reset(PoseEstimate{});
  swap_to(rig, running, "raw_eg");
  rig.drive(kVxMps, 0.0, 0.0, 100);
  const std::uint64_t swaps = rig.state().localization_swaps;
  std::filesystem::remove(dir / "swivel_localization_raw_eg.so");

  const StateSnapshot before = rig.state();
  EXPECT_EQ(plugin_error_of([&] { (void)from_dir.create<Localization>("raw_eg"); }),
            "localization plugin 'raw_eg' not found: no swivel_localization_raw_eg.so in " +
                dir.string() + " (set SWIVEL_PLUGIN_PATH or plugin_path to add directories)");
  rig.drive(kVxMps, 0.0, 0.0, 100);
  const StateSnapshot after = rig.state();
  EXPECT_EQ(after.cycle, before.cycle + 100);
  EXPECT_EQ(after.mode, LoopMode::kVelocity);
  EXPECT_EQ(after.fault_count, 0U);
  EXPECT_EQ(after.localization_swaps, swaps);
  EXPECT_EQ(rig.loop->active_localization(), rig.localization.get());
  EXPECT_GT(distance_m(after.estimate.pose, before.estimate.pose), kVxMps * 0.09);
  rig.loop.reset();
  rig.localization.reset();
  std::filesystem::remove_all(dir);
}

TEST(PluginFaults, WrongAbiAtSwapTimeIsRefusedAndTheLoopRunsOn) {
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 100);
  const StateSnapshot before = rig.state();
  EXPECT_EQ(plugin_error_of([&] { (void)rig.make_localization("bad_abi", "{}"); }),
            test_plugin_dir() +
                "/swivel_localization_bad_abi.so: ABI version 999, expected 4 (built for a newer "
                "Swivel: rebuild the plugin against this one's headers)");
  expect_loop_unaffected(rig, before);
}

TEST(PluginFaults, WrongKindAtSwapTimeIsRefusedAndTheLoopRunsOn) {
  FaultRig rig;
  rig.drive(kVxMps, 0.0, 0.0, 100);
  const StateSnapshot before = rig.state();
  EXPECT_EQ(plugin_error_of([&] { (void)rig.make_localization("wrong_kind", "{}"); }),
            test_plugin_dir() +
                "/swivel_localization_wrong_kind.so: kind 'drivetrain', expected 'localization'");
  expect_loop_unaffected(rig, before);
}

}  // namespace
}  // namespace swivel::faults
