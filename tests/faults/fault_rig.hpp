// SPDX-License-Identifier: Apache-2.0
#pragma once
// A control loop on the real plugins, loaded through PluginLoader (sim hardware, a
// drivetrain, a localization), driven with run_cycle() on synthetic time: deterministic,
// no sleeps. Faults come from the sim plugin's run-time hook (swivel_sim_inject_fault, found
// with dlsym on the loaded library), its `faults:` schedule, the test plugins, and the
// command and motion-capture inputs. The loop's log goes to a string for the cause texts.

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/plugin_loader.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::faults {

using InjectFault = int (*)(void* hardware, const char* kind, double duration_s, unsigned module,
                            double value);

inline std::string source_dir() { return SWIVEL_FAULTS_SOURCE_DIR; }
inline std::string test_plugin_dir() { return SWIVEL_FAULTS_TEST_PLUGIN_DIR; }

/// The search path of the rig: the build's plugins, then the test plugins.
inline std::vector<std::string> plugin_search_path() {
  std::vector<std::string> path = PluginLoader::default_search_path();
  path.push_back(test_plugin_dir());
  return path;
}

struct RigOptions {
  std::string robot = "docent";  ///< config/robots/<robot>.yaml
  std::string drivetrain = "differential";
  std::string localization = "raw_eg";
  std::string hardware_params = "{sensor_noise: false, motion_capture: false}";
  std::string drivetrain_params = "{}";
  std::string localization_params = "{}";
  /// Effects of the simulated world on top of the nominal model (the controller's model
  /// stays nominal), e.g. {"gyro_bias", {{"bias_rad_s", 0.05}}}.
  std::map<std::string, EffectParams> world_effects;
  double command_timeout_s = 0.5;
  rt::OdometryCheckOptions odometry_check;  ///< the loop's defaults unless a test says
  MotionLimits limits;                      ///< the loop's motion limits (none unless a test says)
  /// The controlled stop's deceleration where `limits` has none (infinite: zero at once).
  double stop_linear_deceleration_mps2 = std::numeric_limits<double>::infinity();
  /// The published twist's window (the loop's default unless a test says).
  double twist_window_s = rt::LoopOptions{}.twist_window_s;
  /// External gyro and motion-capture sources (none unless a test says).
  rt::ExternalSensorOptions external_sensors;
};

inline PluginContext plugin_context(const std::string& params_yaml, const std::string& path,
                                    const RobotModel& robot) {
  PluginContext ctx;
  ctx.params = YAML::Load(params_yaml);
  ctx.config_file = "faults.yaml";
  ctx.params_path = path;
  ctx.config_dir = source_dir() + "/config";
  ctx.robot = &robot;
  ctx.period_s = 0.001;
  return ctx;
}

class FaultRig {
 public:
  static constexpr double kDtS = 0.001;

  explicit FaultRig(const RigOptions& options = {})
      : loader(plugin_search_path()),
        robot(load_robot_model(source_dir() + "/config/robots/" + options.robot + ".yaml")),
        world(robot),
        log_sink_(std::make_shared<spdlog::sinks::ostream_sink_st>(log_text_)) {
    world.effects = options.world_effects;
    hardware = loader.create<Hardware>("sim");
    hardware->configure(plugin_context(options.hardware_params, "hardware.params", world));
    drivetrain = loader.create<Drivetrain>(options.drivetrain);
    drivetrain->configure(plugin_context(options.drivetrain_params, "drivetrain.params", robot));
    localization = make_localization(options.localization, options.localization_params);
    rt::LoopOptions loop_options;
    loop_options.realtime = false;
    loop_options.rate_hz = 1.0 / kDtS;
    loop_options.command_timeout_s = options.command_timeout_s;
    loop_options.odometry_check = options.odometry_check;
    loop_options.limits = options.limits;
    loop_options.stop_linear_deceleration_mps2 = options.stop_linear_deceleration_mps2;
    loop_options.twist_window_s = options.twist_window_s;
    loop_options.external_sensors = options.external_sensors;
    rt::set_encoder_resolutions(robot, loop_options);  // as the daemon does
    loop = std::make_unique<rt::ControlLoop>(loop_options, *hardware, *drivetrain, *localization,
                                             options.localization.c_str());
    void* library = dlopen(hardware.path().c_str(), RTLD_NOW | RTLD_NOLOAD);
    if (library != nullptr) {
      inject_ = reinterpret_cast<InjectFault>(dlsym(library, "swivel_sim_inject_fault"));
      dlclose(library);  // the instance keeps it loaded
    }
    // The loop logs through spdlog's default logger when its log is drained.
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("faults", log_sink_));
  }

  FaultRig(const FaultRig&) = delete;
  FaultRig& operator=(const FaultRig&) = delete;
  ~FaultRig() {
    loop.reset();
    // The sink writes into this rig: leave spdlog a logger that outlives it.
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("faults_done"));
  }

  /// A configured and reset localization instance (off the loop, as a hot swap builds it).
  PluginInstance<Localization> make_localization(const std::string& name,
                                                 const std::string& params_yaml) {
    auto instance = loader.create<Localization>(name);
    instance->configure(plugin_context(params_yaml, "localization.params", robot));
    instance->reset(PoseEstimate{});
    return instance;
  }

  /// Pushes a velocity command received now.
  bool command(double vx_mps, double vy_mps, double wz_radps) {
    VelocityCommand c;
    c.twist = {vx_mps, vy_mps, wz_radps};
    c.received_s = t_s;
    c.sequence = ++sequence_;
    return loop->push_command(c);
  }

  void step(int cycles = 1) {
    for (int i = 0; i < cycles; ++i) {
      t_s += kDtS;
      loop->run_cycle(t_s);
    }
  }

  /// Cycles with a fresh command every 10 ms, as a 100 Hz command source sends them.
  void drive(double vx_mps, double vy_mps, double wz_radps, int cycles) {
    for (int i = 0; i < cycles; ++i) {
      if (i % 10 == 0) command(vx_mps, vy_mps, wz_radps);
      step();
    }
  }

  /// Injects a sim fault from the next cycle for `duration_s` (0 when accepted).
  int inject(const char* kind, double duration_s, unsigned module = 0, double value = 0.0) {
    if (inject_ == nullptr) return -1;
    return inject_(hardware.get(), kind, duration_s, module, value);
  }
  [[nodiscard]] InjectFault inject_function() const { return inject_; }

  [[nodiscard]] StateSnapshot state() const { return loop->latest(); }

  /// Everything the loop logged so far (drains its ring).
  std::string log() {
    loop->log().drain();
    log_sink_->flush();
    return log_text_.str();
  }

  PluginLoader loader;
  RobotModel robot;  ///< nominal: drivetrain and localization
  RobotModel world;  ///< the sim's: nominal plus RigOptions::world_effects
  PluginInstance<Hardware> hardware;
  PluginInstance<Drivetrain> drivetrain;
  PluginInstance<Localization> localization;
  std::unique_ptr<rt::ControlLoop> loop;
  double t_s = 10.0;

 private:
  std::ostringstream log_text_;
  std::shared_ptr<spdlog::sinks::ostream_sink_st> log_sink_;
  InjectFault inject_ = nullptr;
  std::uint64_t sequence_ = 0;
};

/// Largest |wheel rate setpoint| of the last cycle (what the drivetrain commanded).
inline double max_wheel_setpoint(const StateSnapshot& s) {
  double m = 0.0;
  for (std::uint32_t i = 0; i < s.module_count; ++i) {
    m = std::max(m, std::abs(s.modules[i].wheel_rate_cmd_radps));
  }
  return m;
}

inline double max_steer_setpoint(const StateSnapshot& s) {
  double m = 0.0;
  for (std::uint32_t i = 0; i < s.module_count; ++i) {
    m = std::max(m, std::abs(s.modules[i].steer_rate_cmd_radps));
  }
  return m;
}

inline double distance_m(const Pose2& a, const Pose2& b) {
  return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m);
}

}  // namespace swivel::faults
