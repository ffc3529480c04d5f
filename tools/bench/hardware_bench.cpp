// SPDX-License-Identifier: Apache-2.0
#include "hardware_bench.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "bench_plugins.hpp"
#include "swivel/dynamixel/bus.hpp"
#include "swivel/dynamixel/emulator.hpp"
#include "swivel/rt/control_loop.hpp"
#include "swivel/rt/realtime.hpp"
#include "swivel/rt/timing_stats.hpp"
#include "swivel/stats/summary.hpp"

namespace swivel::bench {
namespace {

namespace dxl = swivel::dynamixel;

struct Case {
  const char* robot;  // robot model file stem
  std::size_t servos;
  std::uint32_t baud;
};

std::vector<std::uint8_t> ids_for(std::size_t servos) {
  std::vector<std::uint8_t> ids;
  for (std::size_t i = 0; i < servos; ++i) ids.push_back(static_cast<std::uint8_t>(i + 1));
  return ids;
}

dxl::Emulator::Options emulator_options(const Case& c, const HardwareSettings& s) {
  dxl::Emulator::Options o;
  o.ids = ids_for(c.servos);
  o.baud = c.baud;
  o.fifo_priority = s.realtime ? s.priority - 1 : 0;
  return o;
}

// 0 for an empty sample (a phase that produced none), else the type-7 quantile.
double percentile(const std::vector<double>& v, double q) {
  return v.empty() ? 0.0 : stats::quantile(v, q);
}

// The Bus Watchdog every servo has armed while measured, as the plugin arms it (its default).
constexpr double kWatchdogS = 0.1;

// The plugin's cycle, back to back: Sync Write of the goals (the wheel servos' velocities and,
// with steering, the steering servos' positions), Sync Read of velocity and position.
struct BusFigures {
  std::vector<double> cycle_us;
  double cycles_per_s = 0.0;
  std::uint64_t failures = 0;
  std::size_t watchdog_expiries = 0;
  bool armed = false;
};

// Torque on and the Bus Watchdog armed on each servo, as the plugin's activation leaves them
// (velocity mode, still goals). False when a servo refused.
bool arm(dxl::Bus& bus, const std::vector<std::uint8_t>& ids) {
  const std::uint8_t mode[] = {dxl::operating_mode::kVelocity};
  const std::uint8_t on[] = {1};
  const std::uint8_t units[] = {
      static_cast<std::uint8_t>(std::lround(kWatchdogS / dxl::kBusWatchdogUnitS))};
  for (const std::uint8_t id : ids) {
    std::uint8_t error = 0;
    for (const auto& [address, value] :
         {std::pair{dxl::address::kOperatingMode, std::span<const std::uint8_t>(mode)},
          std::pair{dxl::address::kTorqueEnable, std::span<const std::uint8_t>(on)},
          std::pair{dxl::address::kBusWatchdog, std::span<const std::uint8_t>(units)}}) {
      if (bus.write(id, address, value, 0.1, error) != dxl::BusResult::kOk || error != 0) {
        return false;
      }
    }
  }
  return true;
}

BusFigures measure_bus(const Case& c, const HardwareSettings& s) {
  const double seconds = s.seconds;
  dxl::Emulator emulator(emulator_options(c, s));
  dxl::SerialPort port;
  port.open(emulator.port(), c.baud);
  dxl::Bus bus(port);
  const std::vector<std::uint8_t> ids = ids_for(c.servos);
  const bool steering = c.servos > 2;
  std::vector<std::uint8_t> wheels;
  std::vector<std::uint8_t> steers;
  for (std::size_t i = 0; i < ids.size(); ++i)
    (steering && i % 2 == 1 ? steers : wheels).push_back(ids[i]);
  std::vector<std::uint8_t> goals(4 * ids.size(), 0);
  std::vector<dxl::SyncReply> replies(ids.size());
  BusFigures f;
  f.armed = arm(bus, ids);
  const double start = monotonic_s();
  double now = start;
  while (now - start < seconds) {
    const double t0 = monotonic_s();
    bool ok =
        bus.sync_write(dxl::address::kGoalVelocity, 4, wheels, {goals.data(), 4 * wheels.size()});
    if (!steers.empty()) {
      ok = ok && bus.sync_write(dxl::address::kGoalPosition, 4, steers,
                                {goals.data(), 4 * steers.size()});
    }
    ok = ok && bus.sync_read(dxl::address::kPresentVelocity, 8, ids, replies, 0.05);
    for (const auto& r : replies) ok = ok && r.result == dxl::BusResult::kOk;
    now = monotonic_s();
    if (!ok) ++f.failures;
    f.cycle_us.push_back((now - t0) * 1e6);
  }
  f.cycles_per_s = static_cast<double>(f.cycle_us.size()) / (now - start);
  f.watchdog_expiries = emulator.watchdog_expiries().size();
  return f;
}

// Sum of the bytes on the wire per cycle at `baud`: the floor the emulation imposes.
double wire_us(const Case& c) {
  const std::size_t n = c.servos;
  const bool steering = n > 2;
  const std::size_t wheels = steering ? n / 2 : n;
  const std::size_t steers = steering ? n / 2 : 0;
  std::size_t bytes = 14 + 5 * wheels;  // Sync Write: header..params + CRC
  if (steers > 0) bytes += 14 + 5 * steers;
  bytes += 14 + n + n * 19;  // Sync Read, n statuses of 8 data bytes
  return static_cast<double>(bytes) * 10.0 / c.baud * 1e6;
}

void floor_lateness(const HardwareSettings& s, rt::LatencyHistogram& lateness) {
  std::thread thread([&] {
    if (s.realtime) (void)rt::make_thread_fifo(s.priority);
    rt::prefault_stack();
    const auto period_ns = static_cast<std::int64_t>(1e9 / s.rate_hz);
    const std::int64_t start_ns = monotonic_ns();
    const auto end_ns = start_ns + static_cast<std::int64_t>(s.seconds * 1e9);
    std::int64_t deadline_ns = start_ns + period_ns;
    while (deadline_ns < end_ns) {
      rt::sleep_until_ns(deadline_ns);
      const std::int64_t woke_ns = monotonic_ns();
      lateness.record(woke_ns - deadline_ns);
      deadline_ns += period_ns;
      if (woke_ns > deadline_ns)
        deadline_ns += ((woke_ns - deadline_ns) / period_ns + 1) * period_ns;
    }
  });
  thread.join();
}

// The ControlLoop at s.rate_hz with the robot's plugins, the dynamixel hardware on an
// emulated bus at c.baud. False (with `why`) when the plugins could not be loaded.
bool loop_lateness(const HardwareSettings& s, const Case& c, rt::TimingReport& report,
                   std::string& end_state, std::string& why) {
  dxl::Emulator emulator(emulator_options(c, s));
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("swivel_bench_hw_" + std::to_string(getpid())))
          .string();
  std::filesystem::create_directories(dir);
  const bool differential = c.servos == 2;
  std::string params = "{port: " + emulator.port() + ", baud: " + std::to_string(c.baud) +
                       ", bus_period_s: 0, reply_timeout_s: 0.05, stale_timeout_s: 0.5, " +
                       "bus_watchdog_s: " + std::to_string(kWatchdogS) + ", ";
  if (differential) {
    params += "left: {id: 1}, right: {id: 2}}";
  } else {
    params += "modules: [";
    for (std::size_t m = 0; m < c.servos / 2; ++m) {
      params += (m == 0 ? "" : ", ") + std::string("{wheel: {id: ") + std::to_string(2 * m + 1) +
                "}, steer: {id: " + std::to_string(2 * m + 2) + "}}";
    }
    params += "]}";
  }
  const std::string config = dir + "/bench.yaml";
  std::ofstream(config) << "robot_model: " << s.robots_dir << "/" << c.robot << ".yaml\n"
                        << "hardware: {plugin: dynamixel, params: " << params << "}\n"
                        << "drivetrain: {plugin: " << (differential ? "differential" : "swpc")
                        << ", params: {max_wheel_rate_radps: 20.0}}\n"
                        << "localization: {plugin: raw_eg, params: {heading_source: encoders}}\n";
  Plugins p;
  load_plugins(config, s.rate_hz, false, p);
  std::filesystem::remove_all(dir);
  if (!p.real) {
    why = p.description;
    return false;
  }
  if (p.hw().activate() != Status::kOk) {
    why = p.hw().last_error();
    return false;
  }
  {
    rt::LoopOptions options;
    options.rate_hz = s.rate_hz;
    options.fifo_priority = s.priority;
    options.realtime = s.realtime;
    rt::ControlLoop loop(options, p.hw(), p.dt(), p.loc(), p.localization_name().c_str());
    (void)loop.start();
    std::uint64_t sequence = 0;
    const double start_s = loop.now_s();
    while (loop.now_s() - start_s < s.seconds) {
      VelocityCommand command;
      command.twist = {0.2, 0.0, 0.0};
      command.received_s = loop.now_s();
      command.sequence = ++sequence;
      loop.push_command(command);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    loop.stop();
    report = loop.timing();
    const StateSnapshot last = loop.latest();
    char text[160];
    std::snprintf(text, sizeof text, "x=%.3f m, faults %llu (last %s), watchdog expiries %zu",
                  last.estimate.pose.x_m, static_cast<unsigned long long>(last.fault_count),
                  fault_code_name(last.fault), emulator.watchdog_expiries().size());
    end_state = text;
  }
  (void)p.hw().deactivate();
  return true;
}

}  // namespace

int run_hardware(const HardwareSettings& s) {
  const std::vector<Case> cases = {
      {"docent", 2, 1000000}, {"docent", 2, 4000000}, {"swpc4", 8, 1000000}, {"swpc4", 8, 4000000}};
  std::printf(
      "swivel-bench hardware: dynamixel plugin on servos emulated on a pty, the wire time of\n"
      "each byte emulated at the baud rate (10 bits per byte, Return Delay Time 0, no USB\n"
      "adapter latency). %.1f s per measurement. Every servo's Bus Watchdog armed (%.2f s),\n"
      "fed by the cycles as the plugin feeds it; an expiry would stop that servo.\n\n",
      s.seconds, kWatchdogS);
  std::printf(
      "bus cycle = Sync Write of goals + Sync Read of velocity and position, back to back\n");
  std::printf("  %-7s %-6s %8s %8s %8s %8s %10s %12s %9s %9s\n", "servos", "Mbps", "wire", "p50",
              "p99", "max", "cycles/s", "max rate p99", "failures", "wd exp");
  for (const Case& c : cases) {
    BusFigures f;
    // On a thread of its own, at the loop's priority (where permitted), like a bus thread.
    std::thread thread([&] {
      if (s.realtime) (void)rt::make_thread_fifo(s.priority);
      f = measure_bus(c, s);
    });
    thread.join();
    const double p99 = percentile(f.cycle_us, 0.99);
    char expiries[16];
    std::snprintf(expiries, sizeof expiries, "%zu", f.watchdog_expiries);
    std::printf("  %-7zu %-6.0f %7.0fus %7.0fus %7.0fus %7.0fus %10.0f %10.0f Hz %9llu %9s\n",
                c.servos, c.baud / 1e6, wire_us(c), percentile(f.cycle_us, 0.5), p99,
                percentile(f.cycle_us, 1.0), f.cycles_per_s, p99 > 0 ? 1e6 / p99 : 0.0,
                static_cast<unsigned long long>(f.failures), f.armed ? expiries : "not armed");
  }
  std::printf(
      "  (max rate p99: the loop rate at which 99%% of cycles get a fresh reading; wd exp: "
      "servos whose watchdog expired)\n\n");

  rt::CpuDmaLatencyRequest dma;
  if (s.realtime) {
    (void)rt::lock_process_memory();
    (void)dma.acquire(0);
  }
  rt::LatencyHistogram floor;
  floor_lateness(s, floor);
  std::printf("loop lateness at %.0f Hz, %s [us]\n", s.rate_hz,
              s.realtime ? "real-time requested" : "SCHED_OTHER");
  std::printf("  %-30s %9s %9s %9s %9s %9s\n", "", "p50", "p99", "p99.9", "max", "overruns");
  std::printf("  %-30s %9.1f %9.1f %9.1f %9.1f %9s\n", "floor (bare sleep)",
              floor.percentile_us(0.5), floor.percentile_us(0.99), floor.percentile_us(0.999),
              floor.max_us(), "-");
  for (const Case& c : cases) {
    rt::TimingReport t;
    std::string end_state;
    std::string why;
    char label[64];
    std::snprintf(label, sizeof label, "loop, %zu servos @ %.0f Mbps", c.servos, c.baud / 1e6);
    if (!loop_lateness(s, c, t, end_state, why)) {
      std::printf("  %-30s not measured: %s\n", label, why.c_str());
      continue;
    }
    std::printf("  %-30s %9.1f %9.1f %9.1f %9.1f %9llu   end: %s\n", label, t.lateness_p50_us,
                t.lateness_p99_us, t.lateness_p999_us, t.lateness_max_us,
                static_cast<unsigned long long>(t.overruns), end_state.c_str());
  }
  return 0;
}

}  // namespace swivel::bench
