// SPDX-License-Identifier: Apache-2.0
// Per-cycle cost of the localization plugins and the differential drivetrain, each loaded
// from its shared library and driven through its interface with a 1 kHz docent-like motion
// (0.3 m/s, gentle turn, gyro valid, a motion-capture sample every 10th cycle for the EKF
// variant that uses them).

#include <benchmark/benchmark.h>
#include <dlfcn.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/localization.hpp"

namespace {

template <class Interface>
class Loaded {
 public:
  Loaded(const char* file, const char* params_yaml, const swivel::RobotModel& robot)
      : handle_(dlopen(file, RTLD_NOW | RTLD_LOCAL)) {
    if (handle_ == nullptr) throw std::runtime_error(std::string("dlopen: ") + dlerror());
    auto entry =
        reinterpret_cast<SwivelPluginEntryPoint>(dlsym(handle_, SWIVEL_PLUGIN_ENTRY_POINT));
    if (entry == nullptr) throw std::runtime_error(std::string(file) + ": no entry point");
    descriptor_ = entry();
    const char* error = nullptr;
    instance_ = static_cast<Interface*>(descriptor_->create(&error));
    if (instance_ == nullptr) throw std::runtime_error(error != nullptr ? error : "create failed");
    swivel::PluginContext ctx;
    ctx.params = YAML::Load(params_yaml);
    ctx.config_file = "bench";
    ctx.params_path = "params";
    ctx.robot = &robot;
    instance_->configure(ctx);
  }
  ~Loaded() {
    descriptor_->destroy(instance_);
    dlclose(handle_);
  }
  Loaded(const Loaded&) = delete;
  Loaded& operator=(const Loaded&) = delete;
  Interface* operator->() { return instance_; }

 private:
  void* handle_ = nullptr;
  const SwivelPluginDescriptor* descriptor_ = nullptr;
  Interface* instance_ = nullptr;
};

swivel::RobotModel docent() {
  swivel::RobotModel robot;
  robot.name = "docent";
  robot.source_file = "bench";
  return robot;
}

void run_localization(benchmark::State& state, const char* file, const char* params,
                      bool with_fixes) {
  const swivel::RobotModel robot = docent();
  Loaded<swivel::Localization> loc(file, params, robot);
  swivel::OdometryIncrement odo;
  odo.dt_s = 0.001;
  odo.delta = swivel::Pose2{3e-4, 1e-8, 5e-5};
  odo.twist = swivel::Twist2{0.3, 0.0, 0.05};
  odo.valid = true;
  swivel::HardwareState readings;
  readings.gyro_valid = true;
  readings.gyro_wz_radps = 0.0501;
  long cycle = 0;
  for ([[maybe_unused]] auto iteration : state) {
    readings.stamp_s = 0.001 * static_cast<double>(++cycle);
    readings.motion_capture.valid = with_fixes && cycle % 10 == 0;
    readings.motion_capture.pose = loc->estimate().pose;
    if (loc->update(odo, readings) != swivel::Status::kOk) {
      state.SkipWithError(loc->last_error());
      break;
    }
    benchmark::DoNotOptimize(loc->estimate());
  }
}

void raw_eg(benchmark::State& s) { run_localization(s, SWIVEL_BENCH_RAW_EG, "{}", false); }
void kalman_ekf(benchmark::State& s) {
  run_localization(s, SWIVEL_BENCH_KALMAN, "{mode: ekf}", false);
}
void kalman_ekf_with_pose_fixes(benchmark::State& s) {
  run_localization(s, SWIVEL_BENCH_KALMAN, "{mode: ekf}", true);
}
void kalman_lcakf(benchmark::State& s) {
  run_localization(s, SWIVEL_BENCH_KALMAN, "{mode: lcakf}", false);
}
void lsm_paper(benchmark::State& s) {
  run_localization(s, SWIVEL_BENCH_LSM, "{mode: paper}", false);
}
// Worst case: a sample stored and a window fitted on every cycle.
void lsm_paper_every_cycle(benchmark::State& s) {
  run_localization(s, SWIVEL_BENCH_LSM, "{mode: paper, sample_distance_m: 0}", false);
}
void lsm_heading_aligned(benchmark::State& s) {
  run_localization(s, SWIVEL_BENCH_LSM, "{mode: heading_aligned}", false);
}

void differential_forward_inverse(benchmark::State& state) {
  const swivel::RobotModel robot = docent();
  Loaded<swivel::Drivetrain> dt(SWIVEL_BENCH_DIFFERENTIAL, "{}", robot);
  swivel::HardwareState prev;
  swivel::HardwareState cur;
  prev.module_count = cur.module_count = 2;
  swivel::OdometryIncrement odo;
  swivel::ActuatorCommand cmd;
  swivel::Twist2 applied;
  const swivel::Twist2 command{0.3, 0.0, 0.05};
  long cycle = 0;
  for ([[maybe_unused]] auto iteration : state) {
    ++cycle;
    prev = cur;
    cur.stamp_s = 0.001 * static_cast<double>(cycle);
    cur.wheel_angle_rad[0] += 0.001 * 3.87;
    cur.wheel_angle_rad[1] += 0.001 * 4.13;
    if (dt->forward(prev, cur, odo) != swivel::Status::kOk ||
        dt->inverse(command, cur, 0.001, cmd, applied) != swivel::Status::kOk) {
      state.SkipWithError(dt->last_error());
      break;
    }
    benchmark::DoNotOptimize(odo);
    benchmark::DoNotOptimize(cmd);
  }
}

}  // namespace

BENCHMARK(raw_eg);
BENCHMARK(kalman_ekf);
BENCHMARK(kalman_ekf_with_pose_fixes);
BENCHMARK(kalman_lcakf);
BENCHMARK(lsm_paper);
BENCHMARK(lsm_paper_every_cycle);
BENCHMARK(lsm_heading_aligned);
BENCHMARK(differential_forward_inverse);
