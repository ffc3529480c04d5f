#include "sim_hardware.hpp"

#include <climits>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/plugin/abi.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::plugins {

void SimHardware::configure(const PluginContext& ctx) {
  if (ctx.robot == nullptr) throw ConfigError("sim hardware: no robot model");
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  const std::string true_model_file = params.string_or("true_model", "");
  sim::SimOptions options;
  options.seed = static_cast<std::uint64_t>(params.integer_or("seed", 1, 0, INT_MAX));
  options.motion_capture = params.boolean_or("motion_capture", true);
  options.sensor_noise = params.boolean_or("sensor_noise", true);
  options.substep_s = params.number_or("substep_s", options.substep_s, 1e-5, 0.01);
  ParamReader slip = params.child("slip");
  sim::NonSystematicErrors& ns = options.nonsystematic;
  ns.wheel_slip_std = slip.number_or("wheel_std", ns.wheel_slip_std, 0.0, 0.5);
  ns.lateral_scrub_std = slip.number_or("lateral_scrub_std", ns.lateral_scrub_std, 0.0, 0.5);
  ns.correlation_time_s =
      slip.number_or("correlation_time_s", ns.correlation_time_s, 1e-3, 1e3);
  slip.finish();
  params.finish();

  RobotModel truth = *ctx.robot;
  if (!true_model_file.empty()) {
    std::filesystem::path path(true_model_file);
    if (path.is_relative() && !ctx.config_dir.empty()) path = ctx.config_dir / path;
    truth = load_robot_model(path.string());
    if (truth.drivetrain != ctx.robot->drivetrain ||
        truth.module_count() != ctx.robot->module_count()) {
      params.fail("true_model", "'" + path.string() +
                                    "' has a different drivetrain or module count than the "
                                    "robot model '" + ctx.robot->source_file + "'");
    }
  }
  try {
    world_.emplace(truth, options);
  } catch (const std::invalid_argument& e) {
    const std::string source = truth.source_file.empty() ? ctx.config_file : truth.source_file;
    throw ConfigError(source + ": " + e.what());
  }
  command_ = ActuatorCommand{};
  command_.module_count = static_cast<std::uint32_t>(truth.module_count());
  started_ = false;
}

Status SimHardware::read(double stamp_s, HardwareState& out) noexcept {
  if (!world_) {
    last_error_ = "sim: not configured";
    return Status::kError;
  }
  if (!std::isfinite(stamp_s)) {
    last_error_ = "sim: non-finite stamp";
    return Status::kError;
  }
  if (!started_) {
    started_ = true;
    start_stamp_s_ = stamp_s;
    last_stamp_s_ = stamp_s;
  }
  if (stamp_s < last_stamp_s_) {
    last_error_ = "sim: stamp went backwards";
    return Status::kError;
  }
  if (world_->step(stamp_s - last_stamp_s_, command_) != Status::kOk) {
    last_error_ = world_->last_error();
    return Status::kError;
  }
  last_stamp_s_ = stamp_s;
  world_->read(out);
  // The world counts from zero; readers expect the daemon's clock.
  out.stamp_s = stamp_s;
  out.motion_capture.stamp_s += start_stamp_s_;
  return Status::kOk;
}

Status SimHardware::write(const ActuatorCommand& command) noexcept {
  if (!world_) {
    last_error_ = "sim: not configured";
    return Status::kError;
  }
  if (command.module_count != command_.module_count) {
    last_error_ = "sim: command module count differs from the robot's";
    return Status::kError;
  }
  for (std::uint32_t i = 0; i < command.module_count; ++i) {
    if (!std::isfinite(command.wheel_rate_radps[i]) ||
        !std::isfinite(command.steer_rate_radps[i])) {
      last_error_ = "sim: non-finite actuator setpoint";
      return Status::kError;
    }
    if (static_cast<std::uint8_t>(command.mode[i]) >
        static_cast<std::uint8_t>(ModuleDriveMode::kFreeSteer)) {
      last_error_ = "sim: unknown module drive mode";
      return Status::kError;
    }
  }
  command_ = command;
  return Status::kOk;
}

bool SimHardware::ground_truth(Pose2& out) const noexcept {
  if (!world_) return false;
  out = world_->true_pose();
  return true;
}

}  // namespace swivel::plugins

#ifndef SWIVEL_SIM_NO_EXPORT
SWIVEL_EXPORT_PLUGIN(swivel::plugins::SimHardware, swivel::Hardware, "sim")
#endif
