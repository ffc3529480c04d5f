// SPDX-License-Identifier: Apache-2.0
// swivel-bench loop (swap: see swap_bench.hpp): how much wake-up lateness the control loop adds to
// what the machine itself delivers. Two phases alternate in short blocks, floor then loop,
// A B A B ...: (a) the floor, a bare clock_nanosleep loop at the same period and scheduling;
// (b) the ControlLoop with the docent plugins (sim, differential, raw_eg), loaded afresh for
// each block like the daemon loads them, or in-process fakes when they cannot be loaded. A
// burst of the hypervisor or of a neighbour then lands in one block of one pair instead of in
// one whole phase. Each pair gives a loop/floor ratio, reported as its median and spread over
// the pairs; the blocks of each phase are pooled for the percentiles, and the default length
// puts at least 100 samples beyond p99.9 of each phase.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
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
#include "swivel/cli/command_line.hpp"
#include "swivel/rt/control_loop.hpp"
#include "swivel/rt/realtime.hpp"
#include "swivel/rt/timing_stats.hpp"
#include "swivel/stats/summary.hpp"

namespace {

using swivel::rt::LatencyHistogram;

// Samples per phase by default: p99.9 then rests on the 110 largest.
constexpr double kDefaultSamplesPerPhase = 110'000.0;

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
  double seconds = 0.0;  ///< per phase; 0: kDefaultSamplesPerPhase periods
  double block_s = 1.0;
  double rate_hz = 1000.0;
  int priority = 80;
  bool realtime = true;
  bool fakes = false;
  std::string config = SWIVEL_DEFAULT_CONFIG;

  [[nodiscard]] double phase_s() const {
    return seconds > 0.0 ? seconds : kDefaultSamplesPerPhase / rate_hz;
  }
  [[nodiscard]] int blocks() const {
    return std::max(1, static_cast<int>(std::lround(phase_s() / block_s)));
  }
};

void add_unique(std::vector<std::string>& to, const std::string& warning) {
  if (!warning.empty() && std::find(to.begin(), to.end(), warning) == to.end()) {
    to.push_back(warning);
  }
}

// One floor block: nothing but the absolute-time sleep and the clock reads the loop also does.
void run_floor_block(const Settings& s, LatencyHistogram& lateness, std::uint64_t& overruns,
                     std::vector<std::string>& warnings) {
  std::string scheduling_warning;
  std::thread thread([&] {
    if (s.realtime) scheduling_warning = swivel::rt::make_thread_fifo(s.priority);
    swivel::rt::prefault_stack();
    const auto period_ns = static_cast<std::int64_t>(1e9 / s.rate_hz);
    const std::int64_t start_ns = swivel::monotonic_ns();
    const auto end_ns = start_ns + static_cast<std::int64_t>(s.block_s * 1e9);
    std::int64_t deadline_ns = start_ns + period_ns;
    while (deadline_ns < end_ns) {
      swivel::rt::sleep_until_ns(deadline_ns);
      const std::int64_t woke_ns = swivel::monotonic_ns();
      lateness.record(woke_ns - deadline_ns);
      deadline_ns += period_ns;
      if (woke_ns > deadline_ns) {
        ++overruns;
        deadline_ns += ((woke_ns - deadline_ns) / period_ns + 1) * period_ns;
      }
    }
  });
  thread.join();
  add_unique(warnings, scheduling_warning);
}

struct LoopPhase {
  LatencyHistogram lateness;  ///< pooled over the blocks
  LatencyHistogram cycle;
  std::uint64_t overruns = 0;
  swivel::StateSnapshot last;  ///< of the last block
  std::string description;     ///< of the plugins
};

// One loop block: fresh plugins, a ControlLoop started, driven by a command source like the
// daemon's script (50 Hz, a gentle curve), stopped. Returns the block's own lateness
// percentiles through `block`.
void run_loop_block(const Settings& s, LoopPhase& phase, LatencyHistogram& block,
                    std::vector<std::string>& warnings) {
  swivel::bench::Plugins p;
  swivel::bench::load_plugins(s.config, s.rate_hz, s.fakes, p);
  phase.description = p.description;
  swivel::rt::LoopOptions options;
  options.rate_hz = s.rate_hz;
  options.fifo_priority = s.priority;
  options.realtime = s.realtime;
  // As the daemon: the twist window's covariance runs its forward-kinematics calls.
  if (p.real) swivel::rt::set_encoder_resolutions(p.robot, options);
  auto loop = std::make_unique<swivel::rt::ControlLoop>(options, p.hw(), p.dt(), p.loc(),
                                                        p.localization_name().c_str());
  for (const auto& w : loop->start()) add_unique(warnings, w);
  std::uint64_t sequence = 0;
  const double start_s = loop->now_s();
  while (loop->now_s() - start_s < s.block_s) {
    swivel::VelocityCommand c;
    const bool turning = static_cast<int>(2.0 * (loop->now_s() - start_s)) % 2 == 1;
    c.twist = {0.3, 0.0, turning ? 0.6 : 0.0};
    c.received_s = loop->now_s();
    c.sequence = ++sequence;
    loop->push_command(c);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  loop->stop();
  const auto& stats = loop->timing_stats();
  block.add(stats.lateness());
  phase.lateness.add(stats.lateness());
  phase.cycle.add(stats.cycle_time());
  phase.overruns += loop->timing().overruns;
  phase.last = loop->latest();
}

void print_row(const char* label, const LatencyHistogram& h) {
  std::printf("  %-22s %9.1f %9.1f %9.1f %9.1f %9llu\n", label, h.percentile_us(0.5),
              h.percentile_us(0.99), h.percentile_us(0.999), h.max_us(),
              static_cast<unsigned long long>(h.count()));
}

std::string ratio(double loop, double floor) {
  if (floor <= 0.0) return "n/a";
  char text[32];
  std::snprintf(text, sizeof text, "%.2fx", loop / floor);
  return text;
}

void print_spread(const char* label, const std::vector<double>& ratios) {
  if (ratios.empty()) {
    std::printf("  %-10s no pair with a non-zero floor\n", label);
    return;
  }
  const swivel::stats::Summary r = swivel::stats::summarize(ratios);
  std::printf("  %-10s %8.2fx   [%.2fx, %.2fx]   %.2fx .. %.2fx   (%zu pairs)\n", label, r.median,
              r.lower_quartile, r.upper_quartile, r.min, r.max, r.count);
}

int run(const Settings& s) {
  const int blocks = s.blocks();
  std::printf(
      "swivel-bench loop: %d pairs of %.1f s blocks, floor then loop (%.0f s per phase, %.0f s "
      "in all), at %.0f Hz (period %.0f us), %s\n",
      blocks, s.block_s, blocks * s.block_s, 2.0 * blocks * s.block_s, s.rate_hz, 1e6 / s.rate_hz,
      s.realtime ? ("real-time requested: SCHED_FIFO " + std::to_string(s.priority) +
                    ", mlockall, cpu_dma_latency 0")
                       .c_str()
                 : "real-time not requested (SCHED_OTHER)");
  std::fflush(stdout);

  // Process-wide settings held for both phases so that they are measured alike.
  swivel::rt::CpuDmaLatencyRequest dma;
  std::vector<std::string> warnings;
  if (s.realtime) {
    add_unique(warnings, swivel::rt::lock_process_memory());
    add_unique(warnings, dma.acquire(0));
  }
  auto floor = std::make_unique<LatencyHistogram>();
  auto loop = std::make_unique<LoopPhase>();
  auto floor_block = std::make_unique<LatencyHistogram>();
  auto loop_block = std::make_unique<LatencyHistogram>();
  std::uint64_t floor_overruns = 0;
  std::vector<double> ratio_p50;
  std::vector<double> ratio_p99;
  for (int i = 0; i < blocks; ++i) {
    floor_block->reset();
    loop_block->reset();
    run_floor_block(s, *floor_block, floor_overruns, warnings);
    run_loop_block(s, *loop, *loop_block, warnings);
    floor->add(*floor_block);
    const double f50 = floor_block->percentile_us(0.5);
    const double f99 = floor_block->percentile_us(0.99);
    if (f50 > 0.0) ratio_p50.push_back(loop_block->percentile_us(0.5) / f50);
    if (f99 > 0.0) ratio_p99.push_back(loop_block->percentile_us(0.99) / f99);
  }
  std::printf("loop phase runs: %s\n", loop->description.c_str());
  for (const auto& w : warnings) std::printf("warning: %s\n", w.c_str());

  const auto& f = *floor;
  const auto& l = loop->lateness;
  std::printf("\npooled over the blocks of each phase\n");
  std::printf("  %-22s %9s %9s %9s %9s %9s   [us]\n", "", "p50", "p99", "p99.9", "max", "samples");
  print_row("floor lateness", f);
  print_row("loop lateness", l);
  std::printf("  %-22s %9s %9s %9s %9s\n", "ratio loop/floor",
              ratio(l.percentile_us(0.5), f.percentile_us(0.5)).c_str(),
              ratio(l.percentile_us(0.99), f.percentile_us(0.99)).c_str(),
              ratio(l.percentile_us(0.999), f.percentile_us(0.999)).c_str(),
              ratio(l.max_us(), f.max_us()).c_str());
  print_row("loop cycle time", loop->cycle);
  const auto beyond = [](const LatencyHistogram& h) {
    return static_cast<unsigned long long>(static_cast<double>(h.count()) * 0.001);
  };
  std::printf("  p99.9 rests on the %llu (floor) and %llu (loop) largest samples%s\n", beyond(f),
              beyond(l),
              std::min(beyond(f), beyond(l)) < 100 ? ": fewer than 100, a rough figure" : "");

  std::printf("\nloop/floor lateness ratio per pair (floor block, then loop block of %.1f s)\n",
              s.block_s);
  std::printf("  %-10s %9s   %-16s   %s\n", "", "median", "[IQR]", "min .. max");
  print_spread("p50", ratio_p50);
  print_spread("p99", ratio_p99);

  std::printf("\n  cycles: floor %llu, loop %llu; overruns: floor %llu, loop %llu\n",
              static_cast<unsigned long long>(f.count()),
              static_cast<unsigned long long>(l.count()),
              static_cast<unsigned long long>(floor_overruns),
              static_cast<unsigned long long>(loop->overruns));
  const auto& last = loop->last;
  std::printf(
      "  last loop block's end state: pose x=%.3f m y=%.3f m yaw=%.3f rad, faults %llu (last "
      "%s), mode %s\n",
      last.estimate.pose.x_m, last.estimate.pose.y_m, last.estimate.pose.yaw_rad,
      static_cast<unsigned long long>(last.fault_count), swivel::fault_code_name(last.fault),
      mode_name(last.mode));
  return 0;
}

}  // namespace

// The benchmarks behind main(), which reports what escapes them.
static int bench_main(int argc, char** argv) {
  CLI::App app{"Swivel benchmarks"};
  app.require_subcommand(1);
  Settings settings;
  auto* loop = app.add_subcommand(
      "loop",
      "bare clock_nanosleep loop (the floor) and the ControlLoop with plugins, in alternate "
      "blocks");
  loop->add_option("--seconds", settings.seconds,
                   "duration of each phase, s (default: 110 000 periods, 110 s at 1 kHz)")
      ->check(CLI::Range(0.1, 3600.0));
  loop->add_option("--block-s", settings.block_s, "length of one block, s")
      ->check(CLI::Range(0.05, 60.0))
      ->capture_default_str();
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
      "swap",
      "localization hot swaps on the running loop: request to the new plugin's first update");
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
  hardware
      ->add_option("--robots", hardware_settings.robots_dir,
                   "directory with docent.yaml and swpc4.yaml")
      ->check(CLI::ExistingDirectory);
#endif
  if (const auto exit = swivel::cli::parse(app, argc, argv, "swivel-bench")) return *exit;
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

int main(int argc, char** argv) {
  try {
    return bench_main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swivel-bench: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "swivel-bench: an exception that is not a std::exception\n");
  }
  return 1;
}
