// SPDX-License-Identifier: Apache-2.0
// The swpc_geometric plugin run the way the daemon runs it: the real loop (run_cycle on
// synthetic time), the sim and swpc plugins loaded through PluginLoader on
// config/robots/swpc4.yaml, a simulated world whose true parameters differ from the nominal
// ones, and the daemon's CalibrationRunner taking the instance back, analysing it and
// writing the calibrated model.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "alloc_guard.hpp"
#include "calibration_output.hpp"
#include "calibration_runner.hpp"
#include "swivel/plugin/calibration.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/plugin_loader.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel {
namespace {

namespace fs = std::filesystem;
constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kPeriodS = 0.001;

// Forwards to the sim and keeps the last command; can make the readings non-finite.
class RecordingHardware final : public Hardware {
 public:
  explicit RecordingHardware(Hardware& inner) : inner_(inner) {}
  void configure(const PluginContext&) override {}
  Status read(double stamp_s, HardwareState& out) noexcept override {
    const Status s = inner_.read(stamp_s, out);
    if (inject_nan) out.wheel_angle_rad[1] = std::numeric_limits<double>::quiet_NaN();
    return s;
  }
  Status write(const ActuatorCommand& command) noexcept override {
    last = command;
    ++writes;
    return inner_.write(command);
  }
  bool ground_truth(Pose2& out) const noexcept override { return inner_.ground_truth(out); }

  ActuatorCommand last{};
  std::uint64_t writes = 0;
  bool inject_nan = false;

 private:
  Hardware& inner_;
};

// The loop needs a localization; the calibration does not use it.
class NullLocalization final : public Localization {
 public:
  void configure(const PluginContext&) override {}
  void reset(const PoseEstimate& initial) override { estimate_ = initial; }
  Status hand_over(const PoseEstimate& current) noexcept override {
    estimate_ = current;
    return Status::kOk;
  }
  Status update(const OdometryIncrement&, const HardwareState&) noexcept override {
    return Status::kOk;
  }
  [[nodiscard]] PoseEstimate estimate() const noexcept override { return estimate_; }

 private:
  PoseEstimate estimate_{};
};

// True parameters: every module off its design values by amounts of the size the paper
// found (Table 4), each wheel radius by its own amount (the torque-driven free wheels roll
// as the rotation asks, so each radius is observable).
RobotModel true_model(const RobotModel& nominal) {
  RobotModel truth = nominal;
  const double dx_mm[] = {1.5, -1.0, 0.8, -1.2};
  const double dy_mm[] = {-0.9, 1.3, -1.1, 0.7};
  const double delta_deg[] = {2.0, -3.0, 1.5, -2.5};
  const double d_mm[] = {20.8, 19.4, 21.0, 19.7};
  const double r_mm[] = {56.1, 54.4, 55.6, 54.8};
  for (std::size_t i = 0; i < truth.modules.size(); ++i) {
    SwpcModuleParams& m = truth.modules[i];
    m.x_m += dx_mm[i] * 1e-3;
    m.y_m += dy_mm[i] * 1e-3;
    m.steering_offset_rad = delta_deg[i] * kDegToRad;
    m.caster_offset_m = d_mm[i] * 1e-3;
    m.wheel_radius_m = r_mm[i] * 1e-3;
  }
  return truth;
}

// A fast procedure: 90 degrees per run at 0.6 rad/s.
constexpr const char* kFastProcedure =
    "{yaw_rate_radps: 0.6, rotation_deg: 90, settle_s: 0.6, stop_s: 0.2, align_hold_s: 0.05}";

class CalibrationRig {
 public:
  CalibrationRig() : loader_(PluginLoader::default_search_path()) {
    const char* source = std::getenv("SWIVEL_SOURCE_DIR");
    const std::string source_dir = source != nullptr ? source : SWIVEL_TEST_SOURCE_DIR;
    dir_ = fs::temp_directory_path() /
           ("swivel-calibration-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    model_path_ = (dir_ / "swpc4.yaml").string();
    fs::copy_file(fs::path(source_dir) / "config/robots/swpc4.yaml", model_path_);
    nominal_ = load_robot_model(model_path_);
    truth_ = true_model(nominal_);
    save_robot_model(truth_, (dir_ / "truth.yaml").string());

    PluginContext ctx;
    ctx.robot = &nominal_;
    ctx.period_s = kPeriodS;
    ctx.config_dir = dir_.string();
    ctx.config_file = (dir_ / "swiveld.yaml").string();
    ctx.params_path = "hardware.params";
    ctx.params = YAML::Load("{true_model: truth.yaml, seed: 11}");
    sim_ = loader_.create<Hardware>("sim");
    sim_->configure(ctx);
    ctx.params_path = "drivetrain.params";
    ctx.params = YAML::Node();
    drivetrain_ = loader_.create<Drivetrain>("swpc");
    drivetrain_->configure(ctx);
    hardware_ = std::make_unique<RecordingHardware>(*sim_);

    rt::LoopOptions options;
    options.realtime = false;
    options.rate_hz = 1.0 / kPeriodS;
    loop_ =
        std::make_unique<rt::ControlLoop>(options, *hardware_, *drivetrain_, localization_, "none");
    PluginContext cal;
    cal.period_s = kPeriodS;
    cal.config_file = ctx.config_file;
    cal.params_path = "calibration.params";
    cal.config_dir = dir_.string();
    cal.params = YAML::Load(kFastProcedure);
    runner_ = std::make_unique<daemon::CalibrationRunner>(
        *loop_, loader_, nominal_, model_path_, cal, "swpc_geometric",
        [this](const dds::CalibrationSample& s) { published.push_back(s); });
    runner_->set_progress_period(0.0);
  }
  CalibrationRig(const CalibrationRig&) = delete;
  CalibrationRig& operator=(const CalibrationRig&) = delete;
  ~CalibrationRig() {
    runner_.reset();
    loop_.reset();
    fs::remove_all(dir_);
  }

  // Runs `cycles` loop cycles with the allocation guard armed on this thread, then polls.
  void run(int cycles) {
    {
      test::AllocCounter counter;
      for (int i = 0; i < cycles; ++i) {
        t_s_ += kPeriodS;
        loop_->run_cycle(t_s_);
      }
      const test::HeapCounts c = counter.counts();
      loop_allocations += c.allocations + c.deallocations;
    }
    runner_->poll();
  }
  // Runs until the runner reports an end state (or `max_s` of simulated time).
  std::string run_to_end(double max_s) {
    const double end_s = t_s_ + max_s;
    for (;;) {
      run(100);
      std::string status = runner_->status().status;
      if (status != "running") return status;
      if (t_s_ > end_s) return "timeout";
    }
  }
  // Runs until the procedure is recording (or `max_s`); false if it never did.
  bool run_until_recording(double max_s) {
    const double end_s = t_s_ + max_s;
    while (t_s_ < end_s) {
      run(10);
      Calibration* c = loop_->active_calibration();
      if (c != nullptr && c->progress().phase == CalibrationPhase::kRecording &&
          c->progress().fraction > 0.1) {
        return true;
      }
    }
    return false;
  }
  [[nodiscard]] bool setpoints_zero() const {
    for (std::uint32_t i = 0; i < hardware_->last.module_count; ++i) {
      if (hardware_->last.wheel_rate_radps[i] != 0.0 ||
          hardware_->last.steer_rate_radps[i] != 0.0 ||
          hardware_->last.mode[i] != ModuleDriveMode::kVelocity) {
        return false;
      }
    }
    return hardware_->last.module_count == 4;
  }

  std::vector<dds::CalibrationSample> published;
  std::uint64_t loop_allocations = 0;

  PluginLoader loader_;
  fs::path dir_;
  std::string model_path_;
  RobotModel nominal_;
  RobotModel truth_;
  PluginInstance<Hardware> sim_;
  PluginInstance<Drivetrain> drivetrain_;
  std::unique_ptr<RecordingHardware> hardware_;
  NullLocalization localization_;
  std::unique_ptr<rt::ControlLoop> loop_;
  std::unique_ptr<daemon::CalibrationRunner> runner_;
  double t_s_ = 50.0;
};

TEST(SwpcGeometricPlugin, RecoversTrueParametersOfTheSimulatedRobot) {
  CalibrationRig rig;
  ASSERT_EQ(rig.runner_->start(), "");
  rig.run(1);
  EXPECT_EQ(rig.loop_->latest().mode, LoopMode::kCalibration);

  const std::string end = rig.run_to_end(120.0);
  ASSERT_EQ(end, "done") << rig.runner_->status().text;
  for (int i = 0; i < 200 && rig.runner_->status().status == "running"; ++i) rig.runner_->poll();

  EXPECT_EQ(rig.loop_allocations, 0U) << "heap operations on the loop during the procedure";
  EXPECT_EQ(rig.loop_->latest().mode, LoopMode::kIdle);
  EXPECT_EQ(rig.loop_->latest().fault, FaultCode::kNone);
  EXPECT_TRUE(rig.setpoints_zero());

  // Progress was published while running, then the result with every module.
  ASSERT_GE(rig.published.size(), 3U);
  EXPECT_EQ(rig.published.front().status, "running");
  const dds::CalibrationSample result = rig.runner_->status();
  EXPECT_EQ(result.status, "done");
  ASSERT_EQ(result.modules.size(), 4U);

  // The calibrated model is a new file next to the nominal one, which is unchanged.
  const std::string file = rig.runner_->calibrated_model_file();
  ASSERT_FALSE(file.empty());
  EXPECT_EQ(fs::path(file).parent_path(), fs::path(rig.model_path_).parent_path());
  EXPECT_NE(fs::path(file).filename().string().find("swpc4.calibrated-"), std::string::npos);
  EXPECT_EQ(load_robot_model(rig.model_path_).modules[0].caster_offset_m, 0.020);
  const RobotModel calibrated = load_robot_model(file);
  ASSERT_EQ(calibrated.modules.size(), 4U);

  // Motion capture noise 0.3 mm / 1 mrad at 100 Hz over 90 degree runs: the reported
  // 1-sigma is about 0.04 mm for x, y, d and 0.1-0.12 degrees for delta; the tolerances are
  // about 5 sigma and well below the perturbations (0.7-1.5 mm, 1.5-3 degrees, 0.3-1 mm).
  // Radii: the free wheels are torque-driven (the default) and roll without slipping, so
  // each is found to noise level (reported 1-sigma about 0.007 mm; 0.05 mm is 7 sigma and
  // well below the errors to find, 0.2-1.1 mm).
  for (std::size_t i = 0; i < 4; ++i) {
    const SwpcModuleParams& got = calibrated.modules[i];
    const SwpcModuleParams& want = rig.truth_.modules[i];
    SCOPED_TRACE("module " + std::to_string(i + 1));
    std::printf(
        "module %zu: x %.3f/%.3f mm, y %.3f/%.3f mm, delta %.3f/%.3f deg, d %.3f/%.3f mm, "
        "r %.3f/%.3f mm (recovered/true)\n",
        i + 1, got.x_m * 1e3, want.x_m * 1e3, got.y_m * 1e3, want.y_m * 1e3,
        got.steering_offset_rad / kDegToRad, want.steering_offset_rad / kDegToRad,
        got.caster_offset_m * 1e3, want.caster_offset_m * 1e3, got.wheel_radius_m * 1e3,
        want.wheel_radius_m * 1e3);
    std::printf("  sigma: x %.3f mm, y %.3f mm, delta %.3f deg, d %.3f mm, r %.3f mm\n",
                result.modules[i].sigma_x_m * 1e3, result.modules[i].sigma_y_m * 1e3,
                result.modules[i].sigma_delta_rad / kDegToRad, result.modules[i].sigma_d_m * 1e3,
                result.modules[i].sigma_r_m * 1e3);
    EXPECT_NEAR(got.x_m, want.x_m, 0.25e-3);
    EXPECT_NEAR(got.y_m, want.y_m, 0.25e-3);
    EXPECT_NEAR(got.steering_offset_rad, want.steering_offset_rad, 0.5 * kDegToRad);
    EXPECT_NEAR(got.caster_offset_m, want.caster_offset_m, 0.25e-3);
    EXPECT_NEAR(got.wheel_radius_m, want.wheel_radius_m, 0.05e-3);
    EXPECT_GT(result.modules[i].sigma_x_m, 0.0);
    EXPECT_NEAR(result.modules[i].x_m, got.x_m, 1e-9);
  }
}

TEST(SwpcGeometricPlugin, CancelMidRunStopsWithinOneCycle) {
  CalibrationRig rig;
  ASSERT_EQ(rig.runner_->start(), "");
  ASSERT_TRUE(rig.run_until_recording(30.0));
  EXPECT_FALSE(rig.setpoints_zero());  // the free wheels are driven

  rig.runner_->cancel();
  rig.loop_->run_cycle(rig.t_s_ += kPeriodS);

  EXPECT_TRUE(rig.setpoints_zero());
  const StateSnapshot s = rig.loop_->latest();
  EXPECT_EQ(s.mode, LoopMode::kIdle);
  EXPECT_EQ(s.fault, FaultCode::kCalibrationError);
  rig.runner_->poll();
  EXPECT_EQ(rig.runner_->status().status, "cancelled");
  EXPECT_FALSE(rig.loop_->calibration_in_flight());
  EXPECT_TRUE(rig.runner_->calibrated_model_file().empty());

  // Velocity commands were ignored while calibrating; a fresh one drives again.
  VelocityCommand c;
  c.twist = {0.1, 0.0, 0.0};
  c.received_s = rig.t_s_;
  ASSERT_TRUE(rig.loop_->push_command(c));
  rig.loop_->run_cycle(rig.t_s_ += kPeriodS);
  EXPECT_EQ(rig.loop_->latest().mode, LoopMode::kVelocity);
  EXPECT_EQ(rig.loop_->latest().fault, FaultCode::kNone);
}

TEST(SwpcGeometricPlugin, NonFiniteSensorDuringCalibrationStopsSafely) {
  CalibrationRig rig;
  ASSERT_EQ(rig.runner_->start(), "");
  ASSERT_TRUE(rig.run_until_recording(30.0));

  rig.hardware_->inject_nan = true;
  rig.loop_->run_cycle(rig.t_s_ += kPeriodS);

  EXPECT_TRUE(rig.setpoints_zero());
  const StateSnapshot s = rig.loop_->latest();
  EXPECT_EQ(s.mode, LoopMode::kSafeStop);
  EXPECT_EQ(s.fault, FaultCode::kNonFiniteSensor);
  rig.runner_->poll();
  const dds::CalibrationSample status = rig.runner_->status();
  EXPECT_EQ(status.status, "failed");
  EXPECT_NE(status.text.find("non_finite_sensor"), std::string::npos) << status.text;

  // Still stopped while the fault is latched; a new calibration is refused until cleared.
  rig.hardware_->inject_nan = false;
  ASSERT_EQ(rig.runner_->start(), "");
  rig.run(5);
  EXPECT_EQ(rig.runner_->status().status, "failed");
  EXPECT_NE(rig.runner_->status().text.find("safe stop"), std::string::npos);
  EXPECT_TRUE(rig.setpoints_zero());
}

TEST(SwpcGeometricPlugin, RefusesAConfigurationThatNamesAnUnknownKey) {
  CalibrationRig rig;
  PluginInstance<Calibration> c = rig.loader_.create<Calibration>("swpc_geometric");
  PluginContext ctx;
  ctx.robot = &rig.nominal_;
  ctx.config_file = "swiveld.yaml";
  ctx.params_path = "calibration.params";
  ctx.params = YAML::Load("{rotation_degrees: 90}");
  try {
    c->configure(ctx);
    FAIL() << "configure accepted an unknown key";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("rotation_degrees"), std::string::npos) << e.what();
  }
}

// A plan the procedure cannot carry out names the parameter to change.
TEST(SwpcGeometricPlugin, RefusesAPlanAWheelCannotFollowNamingTheParameter) {
  CalibrationRig rig;
  PluginInstance<Calibration> c = rig.loader_.create<Calibration>("swpc_geometric");
  PluginContext ctx;
  ctx.robot = &rig.nominal_;
  ctx.period_s = kPeriodS;
  ctx.config_file = "swiveld.yaml";
  ctx.params_path = "calibration.params";
  ctx.params = YAML::Load("{yaw_rate_radps: 2.0, max_wheel_rate_radps: 5.0}");
  try {
    c->configure(ctx);
    FAIL() << "configure accepted wheel rates above max_wheel_rate_radps";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("calibration.params.yaw_rate_radps"), std::string::npos) << what;
    EXPECT_NE(what.find("above max_wheel_rate_radps"), std::string::npos) << what;
  }
}

TEST(CalibratedModelPath, NeverNamesAnExistingFile) {
  const fs::path dir =
      fs::temp_directory_path() / ("swivel-cal-path-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::time_t now = 1700000000;
  const std::string first = daemon::calibrated_model_path((dir / "swpc4.yaml").string(), now);
  EXPECT_EQ(fs::path(first).parent_path(), dir);
  EXPECT_EQ(fs::path(first).filename().string().rfind("swpc4.calibrated-", 0), 0U) << first;
  {
    std::FILE* f = std::fopen(first.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fclose(f);
  }
  const std::string second = daemon::calibrated_model_path((dir / "swpc4.yaml").string(), now);
  EXPECT_NE(first, second);
  EXPECT_NE(second.find("-2.yaml"), std::string::npos) << second;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace swivel
