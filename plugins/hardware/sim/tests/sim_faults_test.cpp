// SPDX-License-Identifier: Apache-2.0
// The `sim` plugin's fault injection (params `faults:` and the run-time hook): each kind
// changes exactly the reading or call it names, for exactly its window.

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

#include "sim_hardware.hpp"
#include "swivel/config/config_error.hpp"
#include "test_support.hpp"

extern "C" int swivel_sim_inject_fault(void* hardware, const char* kind, double duration_s,
                                       unsigned module, double value);

namespace swivel::plugins {
namespace {

constexpr double kT0S = 100.0;  // the daemon's clock at the first read
constexpr double kDtS = 0.001;
// Reads happen at whole milliseconds; windows start half-way between two of them.
constexpr double kEncoderStepRad = 2.0 * 3.14159265358979323846 / 4096.0;

class SimFaultsTest : public ::testing::Test {
 protected:
  void SetUp() override { model_ = sim::test::docent(); }

  PluginContext context(const std::string& params_yaml) {
    PluginContext ctx;
    ctx.params = YAML::Load(params_yaml);
    ctx.config_file = "swiveld.yaml";
    ctx.params_path = "hardware.params";
    ctx.robot = &model_;
    return ctx;
  }

  // Configures, starts the clock and sets both wheels turning at 5 rad/s.
  void start(const std::string& faults_yaml) {
    hw_.configure(
        context("{sensor_noise: false, motion_capture: false, faults: " + faults_yaml + "}"));
    ASSERT_EQ(hw_.read(kT0S, state_), Status::kOk);
    ActuatorCommand c;
    c.module_count = 2;
    c.wheel_rate_radps = {5.0, 5.0};
    ASSERT_EQ(hw_.write(c), Status::kOk);
  }

  // Reads at sim time k milliseconds.
  Status read_at(int k) { return hw_.read(kT0S + k * kDtS, state_); }

  std::string config_error(const std::string& faults_yaml) {
    try {
      hw_.configure(context("{faults: " + faults_yaml + "}"));
    } catch (const ConfigError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no ConfigError for " << faults_yaml;
    return {};
  }

  RobotModel model_;
  SimHardware hw_;
  HardwareState state_;
};

TEST_F(SimFaultsTest, NanWheelOnlyInsideItsWindowAndOnlyOnItsModule) {
  start("[{kind: nan_wheel, start_s: 0.0105, duration_s: 0.003, module: 1}]");
  int nan_reads = 0;
  for (int k = 1; k <= 20; ++k) {
    ASSERT_EQ(read_at(k), Status::kOk);
    EXPECT_TRUE(std::isfinite(state_.wheel_angle_rad[0]));
    const bool inside = k >= 11 && k <= 13;
    EXPECT_EQ(std::isnan(state_.wheel_angle_rad[1]), inside) << "read " << k;
    nan_reads += std::isnan(state_.wheel_angle_rad[1]) ? 1 : 0;
  }
  EXPECT_EQ(nan_reads, 3);
}

TEST_F(SimFaultsTest, InfGyroKeepsTheGyroValid) {
  start("[{kind: inf_gyro, start_s: 0.0055, duration_s: 0.002}]");
  for (int k = 1; k <= 10; ++k) {
    ASSERT_EQ(read_at(k), Status::kOk);
    EXPECT_TRUE(state_.gyro_valid);
    EXPECT_EQ(std::isinf(state_.gyro_wz_radps), k == 6 || k == 7) << "read " << k;
  }
}

TEST_F(SimFaultsTest, OutOfRangeWheelJumpsByValueAndBack) {
  start("[{kind: out_of_range_wheel, start_s: 0.0055, duration_s: 0.001, module: 0, value: 50}]");
  double previous = state_.wheel_angle_rad[0];
  for (int k = 1; k <= 10; ++k) {
    ASSERT_EQ(read_at(k), Status::kOk);
    const double step = state_.wheel_angle_rad[0] - previous;
    previous = state_.wheel_angle_rad[0];
    if (k == 6) {
      EXPECT_NEAR(step, 50.0, 0.005 + kEncoderStepRad);  // 5 rad/s * 1 ms + quantization
    } else if (k == 7) {
      EXPECT_NEAR(step, -50.0, 0.005 + kEncoderStepRad);
    } else {
      EXPECT_NEAR(step, 0.005, kEncoderStepRad) << "read " << k;
    }
  }
}

TEST_F(SimFaultsTest, FrozenEncoderHoldsWhileTheWheelTurns) {
  start("[{kind: frozen_encoder, start_s: 0.0205, duration_s: 0.05, module: 1}]");
  for (int k = 1; k <= 20; ++k) ASSERT_EQ(read_at(k), Status::kOk);
  const double held = state_.wheel_angle_rad[1];
  for (int k = 21; k <= 70; ++k) {
    ASSERT_EQ(read_at(k), Status::kOk);
    EXPECT_EQ(state_.wheel_angle_rad[1], held) << "read " << k;
  }
  EXPECT_NEAR(hw_.world()->true_wheel_rad(1), 5.0 * 0.070, 1e-9);  // the world moved on
  ASSERT_EQ(read_at(71), Status::kOk);
  EXPECT_NEAR(state_.wheel_angle_rad[1], 5.0 * 0.071, kEncoderStepRad);  // the truth again
  EXPECT_NEAR(state_.wheel_angle_rad[0], state_.wheel_angle_rad[1], kEncoderStepRad);
}

TEST_F(SimFaultsTest, GyroDropoutClearsGyroValid) {
  start("[{kind: gyro_dropout, start_s: 0.0025, duration_s: 0.003}]");
  for (int k = 1; k <= 8; ++k) {
    ASSERT_EQ(read_at(k), Status::kOk);
    EXPECT_EQ(state_.gyro_valid, !(k >= 3 && k <= 5)) << "read " << k;
  }
}

TEST_F(SimFaultsTest, StallAnswersErrorsWithoutBlockingWhileTheWorldMoves) {
  start("[{kind: stall, start_s: 0.0105, duration_s: 0.01}]");
  for (int k = 1; k <= 10; ++k) ASSERT_EQ(read_at(k), Status::kOk);
  for (int k = 11; k <= 20; ++k) {
    ASSERT_EQ(read_at(k), Status::kError);
    EXPECT_STREQ(hw_.last_error(), "sim: hardware not answering");
  }
  ASSERT_EQ(read_at(21), Status::kOk);
  EXPECT_NEAR(state_.wheel_angle_rad[0], 5.0 * 0.021, kEncoderStepRad);
  EXPECT_EQ(state_.stamp_s, kT0S + 21 * kDtS);
}

TEST_F(SimFaultsTest, ReadAndWriteErrorsNameThemselves) {
  start(
      "[{kind: read_error, start_s: 0.0015, duration_s: 0.001},"
      " {kind: write_error, start_s: 0.0035, duration_s: 0.001}]");
  ASSERT_EQ(read_at(1), Status::kOk);
  ASSERT_EQ(read_at(2), Status::kError);
  EXPECT_STREQ(hw_.last_error(), "sim: injected read error");
  ASSERT_EQ(read_at(3), Status::kOk);
  ASSERT_EQ(read_at(4), Status::kOk);
  ActuatorCommand stop;
  stop.module_count = 2;
  EXPECT_EQ(hw_.write(stop), Status::kError);
  EXPECT_STREQ(hw_.last_error(), "sim: injected write error");
  // The refused zero setpoints were not applied: the wheels still turn.
  ASSERT_EQ(read_at(5), Status::kOk);
  EXPECT_NEAR(hw_.world()->true_wheel_rad(0), 5.0 * 0.005, 1e-9);
  EXPECT_EQ(hw_.write(stop), Status::kOk);
  ASSERT_EQ(read_at(6), Status::kOk);
  EXPECT_NEAR(hw_.world()->true_wheel_rad(0), 5.0 * 0.005, 1e-9);
}

TEST_F(SimFaultsTest, RunTimeInjectionStartsAtTheNextRead) {
  start("[]");
  for (int k = 1; k <= 5; ++k) ASSERT_EQ(read_at(k), Status::kOk);
  ASSERT_TRUE(hw_.inject_fault(SimFaultKind::kNanWheel, 0.0025, 0));
  EXPECT_FALSE(hw_.inject_fault(SimFaultKind::kGyroDropout, 1.0)) << "one pending at a time";
  for (int k = 6; k <= 10; ++k) {
    ASSERT_EQ(read_at(k), Status::kOk);
    EXPECT_EQ(std::isnan(state_.wheel_angle_rad[0]), k <= 8) << "read " << k;
  }
  EXPECT_FALSE(hw_.inject_fault(SimFaultKind::kNanWheel, 1.0, 2)) << "module out of range";
  EXPECT_FALSE(hw_.inject_fault(SimFaultKind::kStall, 0.0)) << "zero duration";
}

TEST_F(SimFaultsTest, CEntryPointInjectsIntoASimInstanceOnly) {
  start("[]");
  Hardware* as_interface = &hw_;
  EXPECT_EQ(swivel_sim_inject_fault(as_interface, "stall", 0.002, 0, 0.0), 0);
  ASSERT_EQ(read_at(1), Status::kError);
  EXPECT_STREQ(hw_.last_error(), "sim: hardware not answering");
  EXPECT_EQ(swivel_sim_inject_fault(as_interface, "wobble", 1.0, 0, 0.0), 2);
  EXPECT_EQ(swivel_sim_inject_fault(as_interface, "nan_wheel", 1.0, 7, 0.0), 3);
  EXPECT_EQ(swivel_sim_inject_fault(nullptr, "stall", 1.0, 0, 0.0), 1);

  class OtherHardware final : public Hardware {
   public:
    void configure(const PluginContext&) override {}
    Status read(double, HardwareState&) noexcept override { return Status::kOk; }
    Status write(const ActuatorCommand&) noexcept override { return Status::kOk; }
  } other;
  Hardware* foreign = &other;
  EXPECT_EQ(swivel_sim_inject_fault(foreign, "stall", 1.0, 0, 0.0), 1);
}

TEST_F(SimFaultsTest, ScheduleErrorsNameTheKeyAndTheAllowedKinds) {
  EXPECT_EQ(config_error("[{kind: wobble, start_s: 1, duration_s: 1}]"),
            "swiveld.yaml:1:12: hardware.params.faults[0].kind: unknown fault kind 'wobble' "
            "(expected one of: nan_wheel, inf_gyro, out_of_range_wheel, frozen_encoder, "
            "gyro_dropout, stall, read_error, write_error)");
  EXPECT_NE(config_error("[{kind: stall, start_s: 1}]")
                .find("hardware.params.faults[0]: missing required key 'duration_s'"),
            std::string::npos);
  EXPECT_NE(config_error("[{kind: stall, start_s: 1, duration_s: 0}]")
                .find("faults[0].duration_s: expected a positive number, got 0"),
            std::string::npos);
  EXPECT_NE(config_error("[{kind: nan_wheel, start_s: 1, duration_s: 1, module: 2}]")
                .find("faults[0].module: expected an integer in [0, 1], got 2"),
            std::string::npos);
  EXPECT_NE(config_error("[{kind: stall, start_s: 1, duration_s: 1, module: 0}]")
                .find("faults[0].module: applies only to nan_wheel, out_of_range_wheel and "
                      "frozen_encoder"),
            std::string::npos);
  EXPECT_NE(config_error("[{kind: gyro_dropout, start_s: 1, duration_s: 1, value: 3}]")
                .find("faults[0].value: applies only to out_of_range_wheel"),
            std::string::npos);
  EXPECT_NE(config_error("[{kind: stall, start_s: 1, duration_s: 1, strat_s: 2}]")
                .find("faults[0].strat_s: unknown key"),
            std::string::npos);
  EXPECT_NE(config_error("{kind: stall}").find("hardware.params.faults: expected a list"),
            std::string::npos);
}

}  // namespace
}  // namespace swivel::plugins
