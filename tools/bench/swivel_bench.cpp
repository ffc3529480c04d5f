// swivel-bench loop (swap: see swap_bench.hpp): how much wake-up lateness the control loop adds to what the machine
// itself delivers. Phase (a) runs a bare clock_nanosleep loop at the same period and
// scheduling (the floor); phase (b) runs the ControlLoop with the docent plugins (sim,
// differential, raw_eg) loaded like the daemon loads them, or in-process fakes when they
// cannot be loaded. Both phases run in this one process, one after the other.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "bench_plugins.hpp"
#ifdef SWIVEL_BENCH_HARDWARE
#include "hardware_bench.hpp"
#endif
#include "swap_bench.hpp"
#include "swivel/rt/control_loop.hpp"
#include "swivel/rt/realtime.hpp"
#include "swivel/rt/timing_stats.hpp"

namespace {

using swivel::rt::LatencyHistogram;

const char* mode_name(swivel::LoopMode mode) {
  switch (mode) {
    case swivel::LoopMode::kIdle: return "idle";
    case swivel::LoopMode::kVelocity: return "velocity";
    case swivel::LoopMode::kCalibration: return "calibration";
    case swivel::LoopMode::kSafeStop: return "safe_stop";
  }
  return "unknown";
}

struct Settings {
  double seconds = 3.0;
  double rate_hz = 1000.0;
  int priority = 80;
  bool realtime = true;
  bool fakes = false;
  std::string config = SWIVEL_DEFAULT_CONFIG;
};

struct FloorResult {
  LatencyHistogram lateness;
  std::uint64_t overruns = 0;
  std::string scheduling_warning;
};

// The floor: nothing but the absolute-time sleep and the clock reads the loop also does.
void run_floor(const Settings& s, FloorResult& result) {
  std::thread thread([&] {
    if (s.realtime) result.scheduling_warning = swivel::rt::make_thread_fifo(s.priority);
    swivel::rt::prefault_stack();
    const auto period_ns = static_cast<std::int64_t>(1e9 / s.rate_hz);
    const std::int64_t start_ns = swivel::rt::monotonic_ns();
    const auto end_ns = start_ns + static_cast<std::int64_t>(s.seconds * 1e9);
    std::int64_t deadline_ns = start_ns + period_ns;
    while (deadline_ns < end_ns) {
      swivel::rt::sleep_until_ns(deadline_ns);
      const std::int64_t woke_ns = swivel::rt::monotonic_ns();
      result.lateness.record(woke_ns - deadline_ns);
      deadline_ns += period_ns;
      if (woke_ns > deadline_ns) {
        ++result.overruns;
        deadline_ns += ((woke_ns - deadline_ns) / period_ns + 1) * period_ns;
      }
    }
  });
  thread.join();
}

struct LoopResult {
  swivel::rt::TimingReport timing;
  swivel::StateSnapshot last;
  std::vector<std::string> warnings;
};

void run_loop(const Settings& s, swivel::bench::Plugins& p, LoopResult& result) {
  swivel::rt::LoopOptions options;
  options.rate_hz = s.rate_hz;
  options.fifo_priority = s.priority;
  options.realtime = s.realtime;
  // As the daemon: the twist window's covariance runs its forward-kinematics calls.
  if (p.real) swivel::rt::set_encoder_resolutions(p.robot, options);
  swivel::rt::ControlLoop loop(options, p.hw(), p.dt(), p.loc(), p.localization_name().c_str());
  result.warnings = loop.start();
  // A command source like the daemon's script: 50 Hz, driving a gentle curve.
  std::uint64_t sequence = 0;
  const double start_s = loop.now_s();
  while (loop.now_s() - start_s < s.seconds) {
    swivel::VelocityCommand c;
    const bool turning = static_cast<int>(loop.now_s() - start_s) % 2 == 1;
    c.twist = {0.3, 0.0, turning ? 0.6 : 0.0};
    c.received_s = loop.now_s();
    c.sequence = ++sequence;
    loop.push_command(c);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  loop.stop();
  result.timing = loop.timing();
  result.last = loop.latest();
}

void print_row(const char* label, double p50, double p99, double p999, double max) {
  std::printf("  %-22s %9.1f %9.1f %9.1f %9.1f\n", label, p50, p99, p999, max);
}

std::string ratio(double loop, double floor) {
  if (floor <= 0.0) return "n/a";
  char text[32];
  std::snprintf(text, sizeof text, "%.2fx", loop / floor);
  return text;
}

int run(const Settings& s) {
  std::printf("swivel-bench loop: %.1f s per phase at %.0f Hz (period %.0f us), %s\n", s.seconds,
              s.rate_hz, 1e6 / s.rate_hz,
              s.realtime ? ("real-time requested: SCHED_FIFO " + std::to_string(s.priority) +
                            ", mlockall, cpu_dma_latency 0")
                               .c_str()
                         : "real-time not requested (SCHED_OTHER)");
  swivel::bench::Plugins plugins;
  swivel::bench::load_plugins(s.config, s.rate_hz, s.fakes, plugins);
  std::printf("loop phase runs: %s\n", plugins.description.c_str());

  // Process-wide settings held for both phases so that they are measured alike.
  swivel::rt::CpuDmaLatencyRequest dma;
  std::vector<std::string> warnings;
  if (s.realtime) {
    if (auto w = swivel::rt::lock_process_memory(); !w.empty()) warnings.push_back(w);
    if (auto w = dma.acquire(0); !w.empty()) warnings.push_back(w);
  }
  auto floor = std::make_unique<FloorResult>();
  run_floor(s, *floor);
  if (!floor->scheduling_warning.empty()) warnings.push_back(floor->scheduling_warning);
  auto loop = std::make_unique<LoopResult>();
  run_loop(s, plugins, *loop);
  for (const auto& w : loop->warnings) {
    if (std::find(warnings.begin(), warnings.end(), w) == warnings.end()) warnings.push_back(w);
  }
  for (const auto& w : warnings) std::printf("warning: %s\n", w.c_str());

  const auto& f = floor->lateness;
  const auto& t = loop->timing;
  std::printf("\n  %-22s %9s %9s %9s %9s   [us]\n", "", "p50", "p99", "p99.9", "max");
  print_row("floor lateness", f.percentile_us(0.5), f.percentile_us(0.99), f.percentile_us(0.999),
            f.max_us());
  print_row("loop lateness", t.lateness_p50_us, t.lateness_p99_us, t.lateness_p999_us,
            t.lateness_max_us);
  std::printf("  %-22s %9s %9s %9s %9s\n", "ratio loop/floor",
              ratio(t.lateness_p50_us, f.percentile_us(0.5)).c_str(),
              ratio(t.lateness_p99_us, f.percentile_us(0.99)).c_str(),
              ratio(t.lateness_p999_us, f.percentile_us(0.999)).c_str(),
              ratio(t.lateness_max_us, f.max_us()).c_str());
  print_row("loop cycle time", t.cycle_p50_us, t.cycle_p99_us, t.cycle_p999_us, t.cycle_max_us);
  std::printf("\n  cycles: floor %llu, loop %llu; overruns: floor %llu, loop %llu\n",
              static_cast<unsigned long long>(f.count()), static_cast<unsigned long long>(t.cycles),
              static_cast<unsigned long long>(floor->overruns),
              static_cast<unsigned long long>(t.overruns));
  const auto& last = loop->last;
  std::printf(
      "  loop end state: pose x=%.3f m y=%.3f m yaw=%.3f rad, faults %llu (last %s), mode %s\n",
      last.estimate.pose.x_m, last.estimate.pose.y_m, last.estimate.pose.yaw_rad,
      static_cast<unsigned long long>(last.fault_count), swivel::fault_code_name(last.fault),
      mode_name(last.mode));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Swivel benchmarks"};
  app.require_subcommand(1);
  Settings settings;
  auto* loop = app.add_subcommand(
      "loop", "bare clock_nanosleep loop (the floor), then the ControlLoop with plugins");
  loop->add_option("--seconds", settings.seconds, "duration of each phase, s")
      ->check(CLI::Range(0.1, 3600.0));
  loop->add_option("--rate-hz", settings.rate_hz, "loop rate, Hz")->check(CLI::Range(1.0, 10000.0));
  loop->add_option("--priority", settings.priority, "SCHED_FIFO priority")
      ->check(CLI::Range(1, 99));
  loop->add_flag("!--no-realtime", settings.realtime,
                 "do not try SCHED_FIFO, mlockall or cpu_dma_latency");
  loop->add_flag("--fakes", settings.fakes, "use in-process fake plugins");
  loop->add_option("--config", settings.config, "daemon configuration naming the plugins")
      ->check(CLI::ExistingFile);
  swivel::bench::SwapSettings swap_settings;
  swap_settings.config = SWIVEL_DEFAULT_CONFIG;
  auto* swap = app.add_subcommand(
      "swap", "localization hot swaps on the running loop: request to the new plugin's first update");
  swap->add_option("--swaps", swap_settings.swaps, "swaps to time (kalman, lsm, raw_eg in turn)")
      ->check(CLI::Range(1, 100000));
  swap->add_option("--interval-s", swap_settings.interval_s, "pause between swaps, s")
      ->check(CLI::Range(0.0, 10.0));
  swap->add_option("--rate-hz", swap_settings.rate_hz, "loop rate, Hz")
      ->check(CLI::Range(1.0, 10000.0));
  swap->add_flag("!--no-realtime", swap_settings.realtime,
                 "do not try SCHED_FIFO, mlockall or cpu_dma_latency");
  swap->add_option("--config", swap_settings.config, "daemon configuration naming the plugins")
      ->check(CLI::ExistingFile);
#ifdef SWIVEL_BENCH_HARDWARE
  swivel::bench::HardwareSettings hardware_settings;
  hardware_settings.robots_dir =
      (std::filesystem::path(SWIVEL_DEFAULT_CONFIG).parent_path() / "robots").string();
  auto* hardware = app.add_subcommand(
      "hardware", "the dynamixel plugin on an emulated bus: bus round trip, loop lateness");
  hardware->add_option("--seconds", hardware_settings.seconds, "duration of each measurement, s")
      ->check(CLI::Range(0.1, 3600.0));
  hardware->add_option("--rate-hz", hardware_settings.rate_hz, "loop rate of the lateness runs")
      ->check(CLI::Range(1.0, 10000.0));
  hardware->add_flag("!--no-realtime", hardware_settings.realtime,
                     "do not try SCHED_FIFO, mlockall or cpu_dma_latency");
  hardware->add_option("--robots", hardware_settings.robots_dir,
                       "directory with docent.yaml and swpc4.yaml")
      ->check(CLI::ExistingDirectory);
#endif
  CLI11_PARSE(app, argc, argv);
  try {
    if (swap->parsed()) return swivel::bench::run_swap(swap_settings);
#ifdef SWIVEL_BENCH_HARDWARE
    if (hardware->parsed()) return swivel::bench::run_hardware(hardware_settings);
#endif
    return run(settings);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swivel-bench: %s\n", e.what());
    return 1;
  }
}
