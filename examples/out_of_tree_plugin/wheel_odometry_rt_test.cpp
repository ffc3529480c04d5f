// SPDX-License-Identifier: Apache-2.0
// The plugin's real-time methods, 100 000 cycles under Swivel's allocation guard: no heap
// operation may happen on the loop thread. Also checks that the odometry is integrated.

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <swivel/plugin/localization.hpp>
#include <swivel/testing/alloc_guard.hpp>

namespace example {
swivel::Localization* make_wheel_odometry();
}

int main() {
  std::unique_ptr<swivel::Localization> plugin(example::make_wheel_odometry());
  swivel::PluginContext ctx;
  ctx.params = YAML::Load("{distance_scale: 1.0}");
  ctx.config_file = "test.yaml";
  ctx.params_path = "localization.params";
  plugin->configure(ctx);
  plugin->reset(swivel::PoseEstimate{});

  swivel::OdometryIncrement step;
  step.valid = true;
  step.dt_s = 0.001;
  step.delta = swivel::Pose2{0.0003, 0.0, 0.0};  // 0.3 m/s straight ahead
  const swivel::HardwareState readings{};
  swivel::test::HeapCounts counts;
  double travelled_m = 0.0;
  {
    const swivel::test::AllocCounter counter;  // arms this thread
    for (int k = 0; k < 100000; ++k) {
      if (plugin->update(step, readings) != swivel::Status::kOk) return 2;
      (void)plugin->estimate();
    }
    travelled_m = plugin->estimate().pose.x_m;
    swivel::PoseEstimate back;
    back.pose = swivel::Pose2{1.0, 2.0, 0.5};
    if (plugin->hand_over(back) != swivel::Status::kOk) return 2;
    counts = counter.counts();
  }
  const double x = plugin->estimate().pose.x_m;
  std::printf(
      "%llu allocations, %llu deallocations over 100000 cycles and a hand-over; "
      "travelled %.6f m (expected 30), x after the hand-over %.3f (expected 1)\n",
      static_cast<unsigned long long>(counts.allocations),
      static_cast<unsigned long long>(counts.deallocations), travelled_m, x);
  if (counts.allocations != 0 || counts.deallocations != 0) return 1;
  if (std::abs(travelled_m - 30.0) > 1e-6) return 3;
  return std::abs(x - 1.0) < 1e-12 ? 0 : 3;
}
