// SPDX-License-Identifier: Apache-2.0
// step() and read() of the world and of the plugin run on the real-time loop: no heap
// operation of any kind (every operator new and delete, and malloc and friends outside
// sanitizer builds: Swivel::alloc_guard), and the calls must do their work meanwhile.

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>

#include "alloc_guard.hpp"
#include "sim_hardware.hpp"
#include "swivel/sim/open_loop.hpp"
#include "swivel/sim/world.hpp"
#include "test_support.hpp"

namespace swivel::sim {
namespace {

using swivel::test::AllocCounter;
using swivel::test::HeapCounts;

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
  HeapCounts counts;
  {
    const AllocCounter counter;
    for (int k = 0; k < 2000; ++k) {
      world.read(hw);
      if (k < 1000) {
        controller.velocity(Twist2{0.2, 0.1, 0.3}, hw, command);
      } else if (k == 1000) {
        controller.calibration(CalibrationMotion{0, 0.8, 0.3}, command, twist);
      }
      world.step(0.01, command);
    }
    counts = counter.counts();
  }
  EXPECT_EQ(counts.allocations, 0U) << "first: " << counts.first_allocation_bytes << " bytes";
  EXPECT_EQ(counts.deallocations, 0U);
  EXPECT_NE(hw.wheel_angle_rad[0], 0.0) << "the world did not move";
}

TEST(NoAllocation, WorldStepWithCasterForces) {
  const RobotModel model = test::swpc4();
  SimOptions options;
  options.caster_forces.steering_yield_rad = 0.03;
  World world(model, options);
  const OpenLoopController controller(model);
  HardwareState hw;
  ActuatorCommand command;
  HeapCounts counts;
  {
    const AllocCounter counter;
    for (int k = 0; k < 2000; ++k) {
      world.read(hw);
      controller.velocity(k < 1000 ? Twist2{0.2, 0.1, 0.3} : Twist2{-0.1, 0.2, -0.2}, hw, command);
      world.step(0.01, command);
    }
    counts = counter.counts();
  }
  EXPECT_EQ(counts.allocations, 0U) << "first: " << counts.first_allocation_bytes << " bytes";
  EXPECT_EQ(counts.deallocations, 0U);
  EXPECT_GT(std::hypot(world.true_pose().x_m, world.true_pose().y_m), 0.1) << "it did not move";
}

TEST(NoAllocation, PluginReadAndWrite) {
  RobotModel model = test::docent();
  plugins::SimHardware hw;
  PluginContext ctx;
  ctx.params = YAML::Load("{slip: {wheel_std: 0.01}}");
  ctx.robot = &model;
  hw.configure(ctx);
  ASSERT_EQ(hw.activate(), Status::kOk) << hw.last_error();
  HardwareState s;
  ActuatorCommand c;
  c.module_count = 2;
  c.wheel_rate_radps = {1.0, 2.0};
  int failed_writes = 0;
  int failed_reads = 0;
  HeapCounts counts;
  {
    const AllocCounter counter;
    for (int k = 0; k < 5000; ++k) {
      if (hw.write(c) != Status::kOk) ++failed_writes;
      if (hw.read(k * 0.001, s) != Status::kOk) ++failed_reads;
    }
    counts = counter.counts();
  }
  EXPECT_EQ(counts.allocations, 0U) << "first: " << counts.first_allocation_bytes << " bytes";
  EXPECT_EQ(counts.deallocations, 0U);
  EXPECT_EQ(failed_writes, 0) << hw.last_error();
  EXPECT_EQ(failed_reads, 0) << hw.last_error();
  // The readings followed the commanded rates (about 5 rad and 10 rad after 5 s).
  EXPECT_EQ(s.module_count, 2U);
  EXPECT_DOUBLE_EQ(s.stamp_s, 4999 * 0.001);
  EXPECT_GT(s.wheel_angle_rad[0], 3.0);
  EXPECT_GT(s.wheel_angle_rad[1], s.wheel_angle_rad[0]);
}

}  // namespace
}  // namespace swivel::sim
