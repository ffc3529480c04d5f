// SPDX-License-Identifier: Apache-2.0
// A daemon meant to run for months must not grow with its reloads. The daemon in process, its
// real-time loop running (no DDS, no file watcher): 1,000 rounds of a localization swap
// (kalman <-> raw_eg, by rewriting the configuration file and reloading) and a reload that
// changes nothing. After a warm-up of 100 rounds, the resident set and the heap in use must
// stay within a fixed band. Before PluginConfig's assignment rebound its params, every swap
// kept the whole configuration document alive (about 70 KB, 63 MB over the 900 rounds).

#include <gtest/gtest.h>
#include <malloc.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "swivel/daemon/daemon.hpp"
#include "swivel/rt/control_loop.hpp"

namespace swivel::daemon {
namespace {

namespace fs = std::filesystem;

constexpr int kWarmUpRounds = 100;
constexpr int kRounds = 1000;
constexpr int kSampleEvery = 100;
// The band above the warm-up's figures. One retained configuration document a round would
// cross both within a few rounds.
constexpr long kResidentBandKiB = 1024;
constexpr long kHeapBandKiB = 256;

struct MemoryUse {
  long resident_kib = 0;  ///< VmRSS
  long heap_kib = 0;      ///< bytes malloc has handed out and not had back
};

MemoryUse memory_use() {
  MemoryUse use;
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) use.resident_kib = std::stol(line.substr(6));
  }
  const struct mallinfo2 info = mallinfo2();
  use.heap_kib = static_cast<long>((info.uordblks + info.hblkhd) / 1024);
  return use;
}

std::string config_text(const std::string& localization) {
  const char* params = localization == "kalman" ? "{mode: ekf}" : "{heading_source: gyro}";
  std::ostringstream text;
  text << "loop: {rate_hz: 1000, realtime: false}\n"
       << "robot_model: " << SWIVEL_SOURCE_DIR << "/config/robots/docent.yaml\n"
       << "hardware: {plugin: sim, params: {seed: 1}}\n"
       << "drivetrain: {plugin: differential, params: {max_wheel_rate_radps: 20.0}}\n"
       << "localization: {plugin: " << localization << ", params: " << params << "}\n"
       << "command: {timeout_s: 0.5, source: none}\n"
       << "logging: {level: warn}\n";
  return text.str();
}

// Written to a new file and renamed over the old one, as editors save.
void write_config(const fs::path& file, const std::string& localization) {
  const fs::path next = file.string() + ".new";
  std::ofstream(next) << config_text(localization);
  fs::rename(next, file);
}

TEST(ReloadSoak, ResidentMemoryStaysInABandOverAThousandSwapsAndReloads) {
  spdlog::set_level(spdlog::level::warn);  // two info lines a reload otherwise
  const fs::path dir = fs::path(testing::TempDir()) / "swivel_reload_soak";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path file = dir / "swiveld.yaml";
  write_config(file, "raw_eg");
  DaemonOptions options;
  options.dds = false;
  options.watch_config = false;
  Daemon daemon(load_daemon_config(file.string()), options);
  daemon.start();

  std::string active = "raw_eg";
  MemoryUse warm;
  long widest_resident_kib = 0;
  long widest_heap_kib = 0;
  for (int round = 1; round <= kRounds; ++round) {
    const std::string next = active == "raw_eg" ? "kalman" : "raw_eg";
    std::string expected = "applied localization ";
    expected.append(active).append(" -> ").append(next);
    write_config(file, next);
    const ReloadResult swapped = daemon.reload("soak swap");
    ASSERT_TRUE(swapped.ok) << "round " << round << ": " << swapped.text;
    ASSERT_EQ(swapped.text, expected)
        << "round " << round << " (the loop must take each swap before the next)";
    active = next;
    const ReloadResult unchanged = daemon.reload("soak reload");
    ASSERT_TRUE(unchanged.ok) << "round " << round << ": " << unchanged.text;
    ASSERT_EQ(unchanged.text, "no live change") << "round " << round;

    if (round % kSampleEvery != 0) continue;
    const MemoryUse now = memory_use();
    std::cout << "after " << round << " rounds: resident " << now.resident_kib
              << " KiB, heap in use " << now.heap_kib << " KiB\n";
    if (round == kWarmUpRounds) {
      warm = now;
    } else if (round > kWarmUpRounds) {
      widest_resident_kib = std::max(widest_resident_kib, now.resident_kib - warm.resident_kib);
      widest_heap_kib = std::max(widest_heap_kib, now.heap_kib - warm.heap_kib);
    }
  }
  EXPECT_STREQ(daemon.loop()->latest().localization_plugin.data(), active.c_str());
  daemon.stop();
  fs::remove_all(dir);

  std::cout << "largest growth over the warm-up's figures: resident " << widest_resident_kib
            << " KiB, heap in use " << widest_heap_kib << " KiB\n";
  EXPECT_LE(widest_resident_kib, kResidentBandKiB)
      << "resident memory grew past the band after " << kWarmUpRounds << " rounds";
  EXPECT_LE(widest_heap_kib, kHeapBandKiB)
      << "the heap in use grew past the band after " << kWarmUpRounds << " rounds";
}

}  // namespace
}  // namespace swivel::daemon
