// SPDX-License-Identifier: Apache-2.0
#include "sim_hardware.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"
#include "swivel/plugin/abi.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::plugins {
namespace {

bool is_wheel_kind(SimFaultKind kind) noexcept {
  return kind == SimFaultKind::kNanWheel || kind == SimFaultKind::kOutOfRangeWheel ||
         kind == SimFaultKind::kFrozenEncoder;
}

std::string kind_list() {
  std::string list;
  for (const char* name : kSimFaultKindNames) {
    list += (list.empty() ? "" : ", ") + std::string(name);
  }
  return list;
}

// One entry of params.faults. `modules` is the robot's module count.
SimFault parse_fault(ParamReader& f, std::size_t modules) {
  SimFault fault;
  const std::string kind_name = f.string("kind");
  const std::optional<SimFaultKind> kind = sim_fault_kind(kind_name.c_str());
  if (!kind) {
    f.fail("kind", "unknown fault kind '" + kind_name + "' (expected one of: " + kind_list() + ")");
  }
  fault.kind = *kind;
  fault.start_s = f.number("start_s", 0.0, 1e9);
  fault.duration_s = f.number("duration_s", 0.0, 1e9);
  if (!(fault.duration_s > 0.0)) f.fail("duration_s", "expected a positive number, got 0");
  if (f.has("module")) {
    if (!is_wheel_kind(fault.kind)) {
      f.fail("module", "applies only to nan_wheel, out_of_range_wheel and frozen_encoder");
    }
    fault.module =
        static_cast<std::uint32_t>(f.integer("module", 0, static_cast<int>(modules) - 1));
  }
  if (f.has("value")) {
    if (fault.kind != SimFaultKind::kOutOfRangeWheel) {
      f.fail("value", "applies only to out_of_range_wheel");
    }
    fault.value_rad = f.number("value", -1e6, 1e6);
  }
  f.finish();
  return fault;
}

}  // namespace

std::optional<SimFaultKind> sim_fault_kind(const char* name) noexcept {
  if (name == nullptr) return std::nullopt;
  for (std::size_t i = 0; i < kSimFaultKindNames.size(); ++i) {
    if (std::strcmp(name, kSimFaultKindNames[i]) == 0) return static_cast<SimFaultKind>(i);
  }
  return std::nullopt;
}

void SimHardware::configure(const PluginContext& ctx) {
  if (ctx.robot == nullptr) throw ConfigError("sim hardware: no robot model");
  ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
  const std::string true_model_file = params.string_or("true_model", "");
  sim::SimOptions options;
  options.seed = static_cast<std::uint64_t>(params.integer_or("seed", 1, 0, INT_MAX));
  options.motion_capture = params.boolean_or("motion_capture", true);
  options.sensor_noise = params.boolean_or("sensor_noise", true);
  options.substep_s = params.number_or("substep_s", options.substep_s, 1e-5, 0.01);
  const auto max_substeps = static_cast<std::int64_t>(
      params.integer_or("max_substeps_per_read", kDefaultMaxSubstepsPerRead, 2, 10000));
  ParamReader slip = params.child("slip");
  sim::NonSystematicErrors& ns = options.nonsystematic;
  ns.wheel_slip_std = slip.number_or("wheel_std", ns.wheel_slip_std, 0.0, 0.5);
  ns.lateral_scrub_std = slip.number_or("lateral_scrub_std", ns.lateral_scrub_std, 0.0, 0.5);
  ns.correlation_time_s = slip.number_or("correlation_time_s", ns.correlation_time_s, 1e-3, 1e3);
  slip.finish();
  const YAML::Node fault_list = params.sequence("faults");
  if (fault_list.size() > kMaxFaults) {
    // snprintf, not std::to_string: see param_reader.cpp (keeps the plugin unloadable).
    char text[64];
    std::snprintf(text, sizeof text, "expected at most %zu faults, got %zu", kMaxFaults,
                  fault_list.size());
    params.fail("faults", text);
  }
  std::array<ActiveFault, kMaxFaults> faults{};
  for (std::size_t i = 0; i < fault_list.size(); ++i) {
    ParamReader f = params.element(fault_list, "faults", i);
    faults[i].fault = parse_fault(f, ctx.robot->module_count());
  }
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
                                    "robot model '" +
                                    ctx.robot->source_file + "'");
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
  start_stamp_s_ = 0.0;
  last_stamp_s_ = 0.0;
  world_stamp_s_ = 0.0;
  max_step_s_ = static_cast<double>(max_substeps) * options.substep_s;
  faults_ = faults;
  fault_count_ = fault_list.size();
  last_wheel_rad_ = {};
  injection_pending_.store(false, std::memory_order_release);
}

bool SimHardware::active(const SimFault& fault, double t_s) noexcept {
  return t_s >= fault.start_s && t_s < fault.start_s + fault.duration_s;
}

void SimHardware::take_injection(double t_s) noexcept {
  if (!injection_pending_.load(std::memory_order_acquire)) return;
  SimFault fault = injected_;
  fault.start_s = t_s;
  std::size_t slot = fault_count_;
  for (std::size_t i = 0; i < fault_count_; ++i) {
    const SimFault& old = faults_[i].fault;
    if (t_s >= old.start_s + old.duration_s) {  // expired: reuse
      slot = i;
      break;
    }
  }
  if (slot < kMaxFaults) {
    faults_[slot] = ActiveFault{fault, false, 0.0};
    if (slot == fault_count_) ++fault_count_;
  } else {
    injections_dropped_.fetch_add(1, std::memory_order_relaxed);
  }
  injection_pending_.store(false, std::memory_order_release);
}

Status SimHardware::apply_faults(double t_s, HardwareState& out) noexcept {
  for (std::size_t i = 0; i < fault_count_; ++i) {
    ActiveFault& a = faults_[i];
    if (!active(a.fault, t_s)) {
      a.frozen = false;  // a later window captures afresh
      continue;
    }
    const std::uint32_t m = a.fault.module;
    switch (a.fault.kind) {
      case SimFaultKind::kNanWheel:
        out.wheel_angle_rad[m] = std::numeric_limits<double>::quiet_NaN();
        break;
      case SimFaultKind::kInfGyro:
        out.gyro_wz_radps = std::numeric_limits<double>::infinity();
        break;
      case SimFaultKind::kOutOfRangeWheel: out.wheel_angle_rad[m] += a.fault.value_rad; break;
      case SimFaultKind::kFrozenEncoder:
        if (!a.frozen) {
          a.frozen = true;
          a.frozen_rad = last_wheel_rad_[m];
        }
        out.wheel_angle_rad[m] = a.frozen_rad;
        break;
      case SimFaultKind::kGyroDropout:
        out.gyro_valid = false;
        out.gyro_wz_radps = 0.0;
        break;
      case SimFaultKind::kStall:
      case SimFaultKind::kReadError:
      case SimFaultKind::kWriteError: break;  // handled before the reading / in write()
    }
  }
  last_wheel_rad_ = out.wheel_angle_rad;
  return Status::kOk;
}

bool SimHardware::inject_fault(SimFaultKind kind, double duration_s, std::uint32_t module,
                               double value_rad) noexcept {
  if (!std::isfinite(duration_s) || !(duration_s > 0.0) || !std::isfinite(value_rad)) {
    return false;
  }
  if (is_wheel_kind(kind) && module >= command_.module_count) return false;
  if (injection_pending_.load(std::memory_order_acquire)) return false;
  injected_ = SimFault{kind, 0.0, duration_s, is_wheel_kind(kind) ? module : 0U, value_rad};
  injection_pending_.store(true, std::memory_order_release);
  return true;
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
    world_stamp_s_ = stamp_s;
  }
  if (stamp_s < last_stamp_s_) {
    last_error_ = "sim: stamp went backwards";
    return Status::kError;
  }
  // At most max_step_s_ of physics per read: after a stall the world catches up over the
  // next reads instead of running thousands of substeps in one cycle.
  const double step_s = std::min(stamp_s - world_stamp_s_, max_step_s_);
  if (world_->step(step_s, command_) != Status::kOk) {
    last_error_ = world_->last_error();
    return Status::kError;
  }
  world_stamp_s_ += step_s;
  last_stamp_s_ = stamp_s;
  const double t_s = stamp_s - start_stamp_s_;
  take_injection(t_s);
  // A device that does not answer leaves nothing to read: the world moved on, `out` is
  // untouched and the gyro's next rate averages over the silence.
  for (std::size_t i = 0; i < fault_count_; ++i) {
    const SimFault& f = faults_[i].fault;
    if (f.kind == SimFaultKind::kStall && active(f, t_s)) {
      last_error_ = "sim: hardware not answering";
      return Status::kError;
    }
    if (f.kind == SimFaultKind::kReadError && active(f, t_s)) {
      last_error_ = "sim: injected read error";
      return Status::kError;
    }
  }
  world_->read(out);
  // The world counts from zero; readers expect the daemon's clock. While catching up, the
  // reading is of the (earlier) time the world has reached.
  out.stamp_s = world_stamp_s_;
  out.motion_capture.stamp_s += start_stamp_s_;
  return apply_faults(t_s, out);
}

Status SimHardware::write(const ActuatorCommand& command) noexcept {
  if (!world_) {
    last_error_ = "sim: not configured";
    return Status::kError;
  }
  if (started_) {
    const double t_s = last_stamp_s_ - start_stamp_s_;
    for (std::size_t i = 0; i < fault_count_; ++i) {
      const SimFault& f = faults_[i].fault;
      if (f.kind == SimFaultKind::kWriteError && active(f, t_s)) {
        last_error_ = "sim: injected write error";
        return Status::kError;
      }
    }
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
        static_cast<std::uint8_t>(ModuleDriveMode::kTorque)) {
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

// The run-time injection hook for code that holds only the plugin instance (see the header).
extern "C" __attribute__((visibility("default"))) int swivel_sim_inject_fault(
    void* hardware, const char* kind, double duration_s, unsigned module, double value) {
  auto* sim = dynamic_cast<swivel::plugins::SimHardware*>(static_cast<swivel::Hardware*>(hardware));
  if (sim == nullptr) return 1;
  const std::optional<swivel::plugins::SimFaultKind> k = swivel::plugins::sim_fault_kind(kind);
  if (!k) return 2;
  if (sim->world() == nullptr) return 1;
  if (!std::isfinite(duration_s) || !(duration_s > 0.0) || !std::isfinite(value)) return 3;
  if (swivel::plugins::is_wheel_kind(*k) && module >= sim->world()->plant().module_count) return 3;
  return sim->inject_fault(*k, duration_s, module, value) ? 0 : 4;
}

#ifndef SWIVEL_SIM_NO_EXPORT
SWIVEL_EXPORT_PLUGIN(swivel::plugins::SimHardware, swivel::Hardware, "sim")
#endif
