// SPDX-License-Identifier: Apache-2.0
#include "calibration_service.hpp"

#include <spdlog/spdlog.h>

#include <exception>
#include <utility>

#include "calibration_runner.hpp"
#include "plugin_set.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {
namespace {

const char* drivetrain_name(DrivetrainKind kind) {
  return kind == DrivetrainKind::kSwpc ? "swpc" : "differential";
}

}  // namespace

CalibrationService::CalibrationService(const DaemonConfig& config, rt::ControlLoop& loop,
                                       PluginLoader& loader, Publish publish)
    : config_(config), publish_(std::move(publish)) {
  if (!config.has_calibration()) return;
  // The runner calls back with its mutex held, from the thread that called it (the DDS
  // subscriber or the main thread), never from the loop.
  runner_ = std::make_unique<CalibrationRunner>(
      loop, loader, config.robot, config.robot_model_path,
      plugin_context(config.calibration, config, config.robot, config.period_s()),
      config.calibration.plugin, [this](const dds::CalibrationSample& sample) {
        if (sample.status != logged_status_ || sample.status != "running") {
          if (sample.status == "failed") {
            spdlog::error("calibration failed: {}", sample.text);
          } else {
            spdlog::info("calibration {}: {}", sample.status, sample.text);
          }
          logged_status_ = sample.status;
        }
        publish_(sample);
      });
  spdlog::info(
      "calibration: plugin {} ready (swivelctl calibrate start); calibrated models "
      "are written next to {}",
      config.calibration.plugin, config.robot_model_path);
}

CalibrationService::~CalibrationService() = default;

bool CalibrationService::busy() const { return runner_ && runner_->status().status == "running"; }

std::string CalibrationService::refusal() const {
  if (config_.robot.drivetrain != DrivetrainKind::kSwpc) {
    return std::string("refused: robot '") + config_.robot.name + "' has a " +
           drivetrain_name(config_.robot.drivetrain) +
           " drivetrain; the calibration (swpc_geometric) needs an swpc robot, and " +
           config_.file + " has no calibration: section";
  }
  return "refused: no calibration configured: add 'calibration: {plugin: swpc_geometric}' to " +
         config_.file + " and restart swiveld";
}

dds::ReplySample CalibrationService::handle(const std::string& argument) {
  dds::ReplySample reply;
  reply.verb = "calibrate";
  spdlog::info("calibrate {} requested", argument.empty() ? "status" : argument);
  if (!runner_) {
    dds::CalibrationSample answer;
    answer.status = "failed";
    answer.text = refusal();
    publish_(answer);
    reply.text = answer.text;
    return reply;
  }
  try {
    if (argument == "start") {
      const std::string refusal = runner_->start();  // publishes either way
      reply.ok = refusal.empty();
      reply.text = reply.ok ? "calibration started" : "refused: " + refusal;
    } else if (argument == "cancel" || argument == "status" || argument.empty()) {
      runner_->handle_request(argument);
      const dds::CalibrationSample status = runner_->status();
      reply.ok = true;
      reply.text =
          (argument == "cancel" ? "cancel requested; " : "") + status.status + ": " + status.text;
    } else {
      runner_->handle_request(argument);
      reply.text =
          "refused: unknown calibrate argument '" + argument + "' (start | cancel | status)";
    }
  } catch (const std::exception& e) {
    reply.text = "refused: " + std::string(e.what());
  }
  return reply;
}

void CalibrationService::poll() noexcept {
  if (!runner_) return;
  try {
    runner_->poll();
  } catch (const std::exception& e) {
    spdlog::error("calibration: {}", e.what());
  }
}

}  // namespace swivel::daemon
