// SPDX-License-Identifier: Apache-2.0
// step() and read() of the world and of the plugin run on the real-time loop: no heap.

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "sim_hardware.hpp"
#include "swivel/sim/open_loop.hpp"
#include "swivel/sim/world.hpp"
#include "test_support.hpp"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

// A replacement operator new has only malloc and free beneath it.
// NOLINTBEGIN(cppcoreguidelines-no-malloc)
void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
// NOLINTEND(cppcoreguidelines-no-malloc)

namespace swivel::sim {
namespace {

TEST(NoAllocation, WorldStepAndReadWithEveryEffect) {
  RobotModel model = test::swpc4();
  model.effects["slip"]["gain_per_radps2"] = 0.01;
  model.effects["actuator_lag"]["time_constant_s"] = 0.05;
  model.effects["sensor_latency"]["delay_s"] = 0.03;
  SimOptions options;
  options.nonsystematic.wheel_slip_std = 0.01;
  options.nonsystematic.lateral_scrub_std = 0.01;
  World world(model, options);
  const OpenLoopController controller(model);
  HardwareState hw;
  ActuatorCommand command;
  Twist2 twist;
  ASSERT_TRUE(controller.calibration(CalibrationMotion{0, 0.8, 0.3}, command, twist));
  const long before = g_allocations.load();
  for (int k = 0; k < 2000; ++k) {
    world.read(hw);
    if (k < 1000) {
      controller.velocity(Twist2{0.2, 0.1, 0.3}, hw, command);
    } else if (k == 1000) {
      controller.calibration(CalibrationMotion{0, 0.8, 0.3}, command, twist);
    }
    world.step(0.01, command);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
}

TEST(NoAllocation, PluginReadAndWrite) {
  RobotModel model = test::docent();
  plugins::SimHardware hw;
  PluginContext ctx;
  ctx.params = YAML::Load("{slip: {wheel_std: 0.01}}");
  ctx.robot = &model;
  hw.configure(ctx);
  HardwareState s;
  ActuatorCommand c;
  c.module_count = 2;
  c.wheel_rate_radps = {1.0, 2.0};
  const long before = g_allocations.load();
  for (int k = 0; k < 5000; ++k) {
    hw.write(c);
    hw.read(k * 0.001, s);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
}

}  // namespace
}  // namespace swivel::sim
