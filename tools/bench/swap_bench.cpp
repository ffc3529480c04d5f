// SPDX-License-Identifier: Apache-2.0
#include "swap_bench.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <stop_token>
#include <thread>
#include <vector>

#include "bench_plugins.hpp"
#include "swivel/rt/control_loop.hpp"
#include "swivel/stats/summary.hpp"

namespace swivel::bench {
namespace {

// 0 for an empty sample (a phase that produced none), else the type-7 quantile.
double percentile(const std::vector<double>& values, double q) {
  return values.empty() ? 0.0 : stats::quantile(values, q);
}

void print_row(const char* label, const std::vector<double>& v) {
  std::printf("  %-40s %9.1f %9.1f %9.1f\n", label, percentile(v, 0.5), percentile(v, 0.99),
              percentile(v, 1.0));
}

}  // namespace

int run_swap(const SwapSettings& s) {
  Plugins plugins;
  load_plugins(s.config, s.rate_hz, false, plugins);
  if (!plugins.real) {
    std::fprintf(stderr, "swivel-bench swap: %s\n", plugins.description.c_str());
    return 1;
  }
  std::printf("swivel-bench swap: %d swaps at %.0f Hz (period %.0f us), %s\n", s.swaps, s.rate_hz,
              1e6 / s.rate_hz, plugins.description.c_str());

  rt::LoopOptions options;
  options.rate_hz = s.rate_hz;
  options.fifo_priority = s.priority;
  options.realtime = s.realtime;
  rt::ControlLoop loop(options, plugins.hw(), plugins.dt(), plugins.loc(),
                       plugins.localization_name().c_str());
  for (const auto& warning : loop.start()) std::printf("warning: %s\n", warning.c_str());

  // A command source like the daemon's script, so that the robot moves during the swaps.
  std::jthread commands([&loop](const std::stop_token& stop) {
    std::uint64_t sequence = 0;
    while (!stop.stop_requested()) {
      VelocityCommand c;
      c.twist = {0.3, 0.0, 0.4};
      c.received_s = loop.now_s();
      c.sequence = ++sequence;
      loop.push_command(c);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });

  const std::array<const char*, 3> names = {"kalman", "lsm", "raw_eg"};
  PluginLoader loader(PluginLoader::default_search_path());
  PluginInstance<Localization> active = std::move(plugins.localization);
  std::vector<double> prepare_us;
  std::vector<double> first_update_us;
  std::vector<double> observed_us;
  const rt::TimingReport before = loop.timing();
  int status = 0;
  for (int i = 0; i < s.swaps; ++i) {
    const char* name = names[static_cast<std::size_t>(i) % names.size()];
    // Off the loop, as the daemon's reload does: create, configure, start from the current pose.
    const double prepare_start_s = loop.now_s();
    auto next = loader.create<Localization>(name);
    next->configure(plugins.context(YAML::Node(YAML::NodeType::Map), "localization"));
    next->reset(loop.latest().estimate);
    const std::uint64_t swaps_before = loop.latest().localization_swaps;
    const double request_s = loop.now_s();
    prepare_us.push_back((request_s - prepare_start_s) * 1e6);
    if (!loop.request_localization_swap(next.get(), name)) {
      std::fprintf(stderr, "swivel-bench swap: the loop refused swap %d\n", i + 1);
      status = 1;
      break;
    }
    StateSnapshot seen = loop.latest();
    const double deadline_s = request_s + 1.0;
    while (seen.localization_swaps == swaps_before && loop.now_s() < deadline_s) {
      std::this_thread::sleep_for(std::chrono::microseconds(50));
      seen = loop.latest();
    }
    if (seen.localization_swaps == swaps_before) {
      std::fprintf(stderr, "swivel-bench swap: swap %d not taken within 1 s\n", i + 1);
      status = 1;
      break;
    }
    // stamp_s is the reading time of the first cycle that ran the new plugin's update.
    first_update_us.push_back((seen.stamp_s - request_s) * 1e6);
    observed_us.push_back((loop.now_s() - request_s) * 1e6);
    if (loop.take_retired_localization() != active.get()) {
      std::fprintf(stderr, "swivel-bench swap: the loop retired an unexpected instance\n");
      status = 1;
      break;
    }
    active = std::move(next);  // destroys and unloads the retired instance, off the loop
    std::this_thread::sleep_for(std::chrono::duration<double>(s.interval_s));
  }
  commands.request_stop();
  commands.join();
  loop.stop();
  const rt::TimingReport after = loop.timing();

  std::printf("\n  %-40s %9s %9s %9s   [us]\n", "", "p50", "p99", "max");
  print_row("prepare off the loop (create+configure)", prepare_us);
  print_row("request -> new plugin's first update", first_update_us);
  print_row("request -> seen by the requesting thread", observed_us);
  std::printf("\n  swaps taken: %zu of %d; loop period %.0f us\n", first_update_us.size(), s.swaps,
              1e6 / s.rate_hz);
  std::printf(
      "  loop over the run: cycles %llu, overruns %llu, lateness p99.9 %.1f us, cycle "
      "time p99.9 %.1f us (max %.1f us)\n",
      static_cast<unsigned long long>(after.cycles - before.cycles),
      static_cast<unsigned long long>(after.overruns - before.overruns), after.lateness_p999_us,
      after.cycle_p999_us, after.cycle_max_us);
  return status;
}

}  // namespace swivel::bench
