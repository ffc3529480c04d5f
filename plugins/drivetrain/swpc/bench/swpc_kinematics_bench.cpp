// SPDX-License-Identifier: Apache-2.0
// Per-cycle cost of the SWPC kinematics: what the drivetrain's inverse() computes (one
// inverse per module, desaturation, the near-zero speed measure) and one least-squares
// forward fit.

#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <random>

#include "swivel/swpc/swpc_kinematics.hpp"

namespace {

using swivel::SwpcModuleParams;
using swivel::Twist2;

struct Fixture {
  std::array<SwpcModuleParams, swivel::kMaxModules> modules{};
  std::array<double, swivel::kMaxModules> phi{};
  std::array<double, swivel::kMaxModules> steer_rate{};
  std::array<double, swivel::kMaxModules> wheel_rate{};
  std::size_t n = 0;

  explicit Fixture(std::size_t count) : n(count) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> pos(-0.3, 0.3);
    std::uniform_real_distribution<double> angle(-3.1, 3.1);
    const Twist2 t{0.3, -0.1, 0.5};
    for (std::size_t i = 0; i < n; ++i) {
      modules[i] = {pos(rng), pos(rng), 0.0, 0.02, 0.055};
      phi[i] = angle(rng);
      const auto rates = swivel::swpc::inverse_module(modules[i], phi[i], t);
      steer_rate[i] = rates.steer_rate_radps;
      wheel_rate[i] = rates.wheel_rate_radps;
    }
  }
};

void bm_inverse(benchmark::State& state) {
  const Fixture f(static_cast<std::size_t>(state.range(0)));
  const std::span<const SwpcModuleParams> modules(f.modules.data(), f.n);
  Twist2 t{0.3, -0.1, 0.5};
  std::array<swivel::swpc::ModuleRates, swivel::kMaxModules> rates{};
  for ([[maybe_unused]] auto iteration : state) {
    benchmark::DoNotOptimize(t);
    for (std::size_t i = 0; i < f.n; ++i) {
      rates[i] = swivel::swpc::inverse_module(f.modules[i], f.phi[i], t);
    }
    const double s = swivel::swpc::desaturation_scale(
        std::span<const swivel::swpc::ModuleRates>(rates.data(), f.n), 40.0, 12.0);
    const double speed = swivel::swpc::max_steering_axis_speed(modules, t) * s;
    for (std::size_t i = 0; i < f.n; ++i) {
      rates[i].wheel_rate_radps *= s;
      rates[i].steer_rate_radps *= s;
    }
    benchmark::DoNotOptimize(rates.data());
    benchmark::DoNotOptimize(speed);
    benchmark::ClobberMemory();
  }
}

void bm_forward(benchmark::State& state) {
  Fixture f(static_cast<std::size_t>(state.range(0)));
  const std::span<const SwpcModuleParams> modules(f.modules.data(), f.n);
  for ([[maybe_unused]] auto iteration : state) {
    benchmark::DoNotOptimize(f.wheel_rate.data());
    auto fit = swivel::swpc::forward(modules, std::span<const double>(f.phi.data(), f.n),
                                     std::span<const double>(f.steer_rate.data(), f.n),
                                     std::span<const double>(f.wheel_rate.data(), f.n));
    benchmark::DoNotOptimize(fit);
  }
}

}  // namespace

BENCHMARK(bm_inverse)->Arg(4)->Arg(16);
BENCHMARK(bm_forward)->Arg(4)->Arg(16);
