// SPDX-License-Identifier: Apache-2.0
// The daemon's recovery paths in process, with its real-time loop running and no DDS: the
// hardware lifecycle in the order the host calls it (the `lifecycle` test plugin writes it
// down), clear and set-pose requests, and a hot swap that rolls back.

#include <dlfcn.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "swivel/daemon/daemon.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const std::string k_test_plugins = SWIVEL_TEST_PLUGIN_DIR;

// swiveld.yaml in a fresh folder; `hardware` and `localization` are plugin slots.
class DaemonFiles {
 public:
  DaemonFiles(const DaemonFiles&) = delete;
  DaemonFiles& operator=(const DaemonFiles&) = delete;
  DaemonFiles(DaemonFiles&&) = delete;
  DaemonFiles& operator=(DaemonFiles&&) = delete;
  explicit DaemonFiles(const std::string& name)
      : dir_(fs::path(testing::TempDir()) / ("swivel_daemon_recovery_" + name)) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~DaemonFiles() { fs::remove_all(dir_); }

  // NOLINTNEXTLINE(modernize-use-nodiscard): a rewrite of the file ignores its path
  std::string write(const std::string& hardware, const std::string& localization) const {
    const fs::path file = dir_ / "swiveld.yaml";
    std::ofstream(file) << "loop: {rate_hz: 1000, realtime: false}\n"
                        << "robot_model: " << SWIVEL_SOURCE_DIR << "/config/robots/docent.yaml\n"
                        << "plugin_path: [" << k_test_plugins << "]\n"
                        << "hardware: " << hardware << "\n"
                        << "drivetrain: {plugin: differential}\n"
                        << "localization: " << localization << "\n"
                        << "command: {timeout_s: 0.5, source: none}\n"
                        << "controlled_stop: {linear_deceleration_mps2: 2.0}\n"
                        << "logging: {level: warn}\n";
    return file.string();
  }

 private:
  fs::path dir_;
};

DaemonOptions in_process() {
  DaemonOptions options;
  options.dds = false;
  options.watch_config = false;
  return options;
}

bool wait_until(const std::function<bool()>& done, double seconds = 5.0) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
  while (!done()) {
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// The lifecycle plugin's exported hooks; the handle keeps its library (and journal) loaded.
class LifecycleProbe {
 public:
  LifecycleProbe(const LifecycleProbe&) = delete;
  LifecycleProbe& operator=(const LifecycleProbe&) = delete;
  LifecycleProbe(LifecycleProbe&&) = delete;
  LifecycleProbe& operator=(LifecycleProbe&&) = delete;
  LifecycleProbe() {
    handle_ = dlopen((k_test_plugins + "/swivel_hardware_lifecycle.so").c_str(), RTLD_NOW);
    if (handle_ == nullptr) return;
    journal_ =
        reinterpret_cast<int (*)(char*, unsigned)>(dlsym(handle_, "swivel_lifecycle_journal"));
    set_ = reinterpret_cast<int (*)(const char*, int)>(dlsym(handle_, "swivel_lifecycle_set"));
  }
  ~LifecycleProbe() {
    if (set_ != nullptr) {
      set_("fail_reads", 0);
      set_("refuse_activate", 0);
    }
    if (handle_ != nullptr) dlclose(handle_);
  }
  [[nodiscard]] bool ok() const { return journal_ != nullptr && set_ != nullptr; }
  [[nodiscard]] std::string journal() const {
    char text[2048];
    journal_(text, sizeof text);
    return text;
  }
  void set(const char* what, bool on) const { ASSERT_EQ(set_(what, on ? 1 : 0), 0); }

 private:
  void* handle_ = nullptr;
  int (*journal_)(char*, unsigned) = nullptr;
  int (*set_)(const char*, int) = nullptr;
};

void wait_cycles(const rt::ControlLoop& loop, std::uint64_t cycles) {
  const std::uint64_t from = loop.latest().cycle;
  ASSERT_TRUE(wait_until([&] { return loop.latest().cycle >= from + cycles; }));
}

dds::RequestSample request(const std::string& verb, std::uint64_t id) {
  dds::RequestSample r;
  r.verb = verb;
  r.request_id = id;
  return r;
}

void push_command(rt::ControlLoop& loop, double vx_mps) {
  VelocityCommand c;
  c.twist.vx_mps = vx_mps;
  c.received_s = loop.now_s();
  (void)loop.push_command(c);
}

TEST(DaemonLifecycle, HardwareHooksAreCalledInTheDocumentedOrder) {
  LifecycleProbe probe;
  ASSERT_TRUE(probe.ok()) << dlerror();
  DaemonFiles files("order");
  Daemon daemon(load_daemon_config(files.write("{plugin: lifecycle}", "{plugin: raw_eg}")),
                in_process());
  EXPECT_EQ(probe.journal(), "configure");
  daemon.start();
  rt::ControlLoop& loop = *daemon.loop();
  ASSERT_TRUE(wait_until([&] { return loop.latest().cycle > 20; }));

  // A bus error: on_error() at the loop's boundary, the robot in safe stop.
  probe.set("fail_reads", true);
  ASSERT_TRUE(wait_until([&] { return loop.latest().hardware_in_error; }));
  EXPECT_EQ(loop.latest().fault, FaultCode::kHardwareError);
  wait_cycles(loop, 10);  // reads go on in the error state

  // While the cause persists: re-activated, but the clear is refused with the cause.
  dds::ReplySample reply = daemon.handle_request(request("clear", 1));
  EXPECT_FALSE(reply.ok);
  EXPECT_EQ(reply.text, "refused: hardware_error persists (lifecycle: injected read error)");
  EXPECT_EQ(reply.request_id, 1U);
  EXPECT_EQ(reply.verb, "clear");

  // Cause gone: re-activated and cleared.
  probe.set("fail_reads", false);
  reply = daemon.handle_request(request("clear", 2));
  EXPECT_TRUE(reply.ok) << reply.text;
  EXPECT_EQ(reply.text, "cleared hardware_error (lifecycle: injected read error)");
  EXPECT_FALSE(loop.latest().hardware_in_error);

  // A second error, and drives that will not enable again: the clear names the plugin's reason.
  probe.set("fail_reads", true);
  ASSERT_TRUE(wait_until([&] { return loop.latest().hardware_in_error; }));
  wait_cycles(loop, 10);
  probe.set("fail_reads", false);
  probe.set("refuse_activate", true);
  reply = daemon.handle_request(request("clear", 3));
  EXPECT_FALSE(reply.ok);
  EXPECT_EQ(reply.text,
            "refused: hardware plugin 'lifecycle' refused to re-activate: lifecycle: drives "
            "refused to enable (planted failure)");
  EXPECT_EQ(loop.latest().mode, LoopMode::kSafeStop);
  probe.set("refuse_activate", false);
  reply = daemon.handle_request(request("clear", 4));
  EXPECT_TRUE(reply.ok) << reply.text;

  // Driving when SIGTERM comes: deactivate() only after the robot came to rest.
  ASSERT_TRUE(wait_until([&] {
    push_command(loop, 0.4);
    return loop.latest().command_twist.vx_mps == 0.4;
  }));
  daemon.stop();
  EXPECT_EQ(probe.journal(),
            "configure activate io on_error io activate io activate io on_error io "
            "activate_refused activate io deactivate");
}

TEST(DaemonLifecycle, HardwareThatRefusesToActivateStopsTheStart) {
  LifecycleProbe probe;
  ASSERT_TRUE(probe.ok()) << dlerror();
  DaemonFiles files("refuse");
  Daemon daemon(load_daemon_config(files.write("{plugin: lifecycle}", "{plugin: raw_eg}")),
                in_process());
  probe.set("refuse_activate", true);
  try {
    daemon.start();
    FAIL() << "started";
  } catch (const PluginError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("swiveld.yaml:4:12: hardware.plugin: plugin 'lifecycle' refused to "
                           "activate: lifecycle: drives refused to enable (planted failure)"),
              std::string::npos)
        << message;
  }
  EXPECT_EQ(daemon.loop(), nullptr);
  daemon.stop();
  EXPECT_EQ(probe.journal(), "configure activate_refused");  // never deactivated: never active
}

TEST(DaemonRequests, SetPoseGoesThroughTheActiveLocalizationOrIsRefusedWithItsReason) {
  DaemonFiles files("set_pose");
  Daemon daemon(load_daemon_config(files.write("{plugin: sim}", "{plugin: raw_eg}")), in_process());
  daemon.start();
  dds::SetPoseSample pose;
  pose.request_id = 12;
  pose.pose.pose = {2.0, -1.0, 0.5};
  dds::ReplySample reply = daemon.set_pose(pose);
  EXPECT_TRUE(reply.ok) << reply.text;
  EXPECT_EQ(reply.request_id, 12U);
  EXPECT_EQ(reply.verb, "set_pose");
  EXPECT_EQ(reply.text,
            "pose set to x=2.000 m y=-1.000 m yaw=0.500 rad, uncertainty kept "
            "(localization raw_eg)");
  // The reply comes from inside the cycle that set the pose, before that cycle publishes its
  // state: the snapshot two cycles on carries it.
  wait_cycles(*daemon.loop(), 2);
  const Pose2 now = daemon.loop()->latest().estimate.pose;
  EXPECT_NEAR(now.x_m, 2.0, 1e-6);  // standing still
  EXPECT_NEAR(now.y_m, -1.0, 1e-6);

  pose.pose.pose.x_m = std::nan("");
  EXPECT_EQ(daemon.set_pose(pose).text,
            "refused: the pose (x_m, y_m, yaw_rad) and its covariance must be finite");
  pose.pose.pose.x_m = 0.0;
  pose.pose.has_covariance = true;
  pose.pose.covariance = {0.01, 0, 0, 0, -0.04, 0, 0, 0, 0.01};
  EXPECT_EQ(daemon.set_pose(pose).text,
            "refused: negative variance (x 0.010000 m^2, y -0.040000 m^2, yaw 0.010000 rad^2)");
  daemon.stop();

  Daemon refusing(load_daemon_config(files.write("{plugin: sim}", "{plugin: refuses_hand_over}")),
                  in_process());
  refusing.start();
  pose.pose.has_covariance = false;
  reply = refusing.set_pose(pose);
  EXPECT_FALSE(reply.ok);
  EXPECT_EQ(reply.text,
            "refused by localization 'refuses_hand_over': no map to place the pose "
            "in (planted refusal)");
  EXPECT_EQ(refusing.loop()->latest().fault, FaultCode::kNone);
}

TEST(DaemonRequests, ClearWithNothingToClearAndUnknownRequestsAreAnswered) {
  DaemonFiles files("answers");
  Daemon daemon(load_daemon_config(files.write("{plugin: sim}", "{plugin: raw_eg}")), in_process());
  daemon.start();
  EXPECT_EQ(daemon.handle_request(request("clear", 1)).text, "nothing to clear");
  const dds::ReplySample unknown = daemon.handle_request(request("reboot", 2));
  EXPECT_FALSE(unknown.ok);
  EXPECT_EQ(unknown.text,
            "refused: unknown request 'reboot' (reload, clear, calibrate; a pose "
            "goes to swivel_set_pose)");
  const dds::ReplySample calibrate = daemon.handle_request(request("calibrate", 3));
  EXPECT_FALSE(calibrate.ok);
  EXPECT_EQ(calibrate.text.rfind("refused: robot 'docent' has a differential drivetrain", 0), 0U)
      << calibrate.text;
  const dds::ReplySample reload = daemon.handle_request(request("reload", 4));
  EXPECT_TRUE(reload.ok) << reload.text;
  EXPECT_EQ(reload.text, "no live change");
}

// A hot swap whose incoming plugin refuses the hand-over: the running localization stays,
// the refused instance is destroyed off the loop (its library unloads), reload reports the
// plugin's reason, and no fault latches.
void expect_rollback(const std::string& incoming, const std::string& reason) {
  DaemonFiles files("rollback");
  const std::string file = files.write("{plugin: sim}", "{plugin: raw_eg}");
  Daemon daemon(load_daemon_config(file), in_process());
  daemon.start();
  rt::ControlLoop& loop = *daemon.loop();
  ASSERT_TRUE(wait_until([&] {
    push_command(loop, 0.2);
    return loop.latest().mode == LoopMode::kVelocity;
  }));
  files.write("{plugin: sim}", incoming);

  const ReloadResult result = daemon.reload("test");

  EXPECT_FALSE(result.ok);
  EXPECT_NE(result.text.find("plugin 'refuses_hand_over' refused the hand-over: " + reason +
                             "; 'raw_eg' stays active"),
            std::string::npos)
      << result.text;
  push_command(loop, 0.2);
  ASSERT_TRUE(wait_until([&] { return loop.latest().cycle > 0; }));
  const StateSnapshot s = loop.latest();
  EXPECT_STREQ(s.localization_plugin.data(), "raw_eg");
  EXPECT_EQ(s.localization_swaps, 0U);
  EXPECT_EQ(s.fault, FaultCode::kNone);
  EXPECT_EQ(s.fault_count, 0U);
  EXPECT_EQ(s.mode, LoopMode::kVelocity);
  EXPECT_EQ(daemon.config().localization.plugin, "raw_eg");
  void* still = dlopen((k_test_plugins + "/swivel_localization_refuses_hand_over.so").c_str(),
                       RTLD_NOW | RTLD_NOLOAD);
  EXPECT_EQ(still, nullptr) << "the refused instance's library is still loaded";
  if (still != nullptr) dlclose(still);

  // The configuration fixed: the next reload swaps.
  files.write("{plugin: sim}", "{plugin: raw_eg, params: {heading_source: encoders}}");
  const ReloadResult fixed = daemon.reload("test");
  EXPECT_TRUE(fixed.ok) << fixed.text;
  EXPECT_EQ(loop.latest().localization_swaps, 1U);
}

TEST(DaemonSwap, RollsBackWhenTheIncomingPluginRefusesTheHandOver) {
  expect_rollback("{plugin: refuses_hand_over}", "no map to place the pose in (planted refusal)");
}

TEST(DaemonSwap, RollsBackWhenTheIncomingPluginThrowsFromTheHandOver) {
  expect_rollback("{plugin: refuses_hand_over, params: {throw: true}}",
                  "plugin threw std::runtime_error: planted exception in hand_over");
}

}  // namespace
}  // namespace swivel::daemon
