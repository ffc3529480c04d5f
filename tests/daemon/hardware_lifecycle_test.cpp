// SPDX-License-Identifier: Apache-2.0
// The daemon's activate/deactivate calls keep what a failing plugin said or threw: the
// reason of a kError, or the type and message of an exception, std or not.

#include "hardware_lifecycle.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <functional>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

namespace swivel::daemon {
namespace {

struct DriveFault {
  int code = 3;
};

// Hardware whose activate() and deactivate() do what the test says.
class ScriptedHardware final : public Hardware {
 public:
  std::function<Status()> on_activate = [] { return Status::kOk; };
  std::function<Status()> on_deactivate = [] { return Status::kOk; };
  const char* error = "";

  void configure(const PluginContext& /*ctx*/) override {}
  Status activate() override { return on_activate(); }
  Status deactivate() override { return on_deactivate(); }
  Status read(double /*stamp_s*/, HardwareState& /*out*/) override { return Status::kOk; }
  Status write(const ActuatorCommand& /*command*/) override { return Status::kOk; }
  [[nodiscard]] const char* last_error() const noexcept override { return error; }
};

// What deactivate_hardware logs, through the default logger.
class CapturedLog {
 public:
  CapturedLog()
      : previous_(spdlog::default_logger()),
        logger_(std::make_shared<spdlog::logger>(
            "captured", std::make_shared<spdlog::sinks::ostream_sink_mt>(text_))) {
    logger_->set_pattern("%l %v");
    spdlog::set_default_logger(logger_);
  }
  ~CapturedLog() { spdlog::set_default_logger(previous_); }
  CapturedLog(const CapturedLog&) = delete;
  CapturedLog& operator=(const CapturedLog&) = delete;
  CapturedLog(CapturedLog&&) = delete;
  CapturedLog& operator=(CapturedLog&&) = delete;

  [[nodiscard]] std::string text() const { return text_.str(); }

 private:
  std::ostringstream text_;
  std::shared_ptr<spdlog::logger> previous_;
  std::shared_ptr<spdlog::logger> logger_;
};

TEST(HardwareLifecycle, ActivateReportsTheReasonOfAKError) {
  ScriptedHardware hw;
  EXPECT_EQ(activate_hardware(hw), "");
  hw.on_activate = [] { return Status::kError; };
  hw.error = "drive 2 did not enable";
  EXPECT_EQ(activate_hardware(hw), "drive 2 did not enable");
  hw.error = "";
  EXPECT_EQ(activate_hardware(hw), "no reason given");
}

TEST(HardwareLifecycle, ActivateKeepsTheTypeAndMessageOfWhatWasThrown) {
  ScriptedHardware hw;
  hw.on_activate = []() -> Status { throw std::runtime_error("bus gone"); };
  EXPECT_EQ(activate_hardware(hw), "threw std::runtime_error: bus gone");
  hw.on_activate = []() -> Status { throw 7; };
  EXPECT_EQ(activate_hardware(hw), "threw int (not a std::exception)");
}

TEST(HardwareLifecycle, DeactivateLogsWhatANonStandardExceptionWas) {
  ScriptedHardware hw;
  hw.on_deactivate = []() -> Status { throw DriveFault{}; };
  const CapturedLog log;
  EXPECT_FALSE(deactivate_hardware(hw, "servo_bus"));
  const std::string text = log.text();
  EXPECT_NE(text.find("error hardware servo_bus failed to deactivate: threw "), std::string::npos)
      << text;
  EXPECT_NE(text.find("DriveFault (not a std::exception)"), std::string::npos) << text;
}

TEST(HardwareLifecycle, DeactivateLogsTheMessageAndTypeOfAStdException) {
  ScriptedHardware hw;
  hw.on_deactivate = []() -> Status { throw std::logic_error("torque still on"); };
  const CapturedLog log;
  EXPECT_FALSE(deactivate_hardware(hw, "servo_bus"));
  EXPECT_NE(log.text().find("failed to deactivate: threw std::logic_error: torque still on"),
            std::string::npos)
      << log.text();
}

TEST(HardwareLifecycle, DeactivateLogsSuccessAndAKErrorsReason) {
  ScriptedHardware hw;
  {
    const CapturedLog log;
    EXPECT_TRUE(deactivate_hardware(hw, "servo_bus"));
    EXPECT_NE(log.text().find("info hardware servo_bus deactivated"), std::string::npos);
  }
  hw.on_deactivate = [] { return Status::kError; };
  hw.error = "drive 1 kept its torque";
  const CapturedLog log;
  EXPECT_FALSE(deactivate_hardware(hw, "servo_bus"));
  EXPECT_NE(log.text().find("failed to deactivate: drive 1 kept its torque"), std::string::npos)
      << log.text();
}

}  // namespace
}  // namespace swivel::daemon
