// SPDX-License-Identifier: Apache-2.0
// swivel-dxl-emulator: a DYNAMIXEL X-series bus on a pseudo-terminal, for trying the
// `dynamixel` hardware plugin without servos.
//
//   swivel-dxl-emulator --ids 1,2 [--baud 1000000] [--link PATH]
//                       [--fault KIND:ID:START_S ...]
//
// Prints the device path (and makes PATH a symbolic link to it with --link), then serves
// until SIGINT or SIGTERM and prints the Torque Enable writes it saw and the Bus Watchdog
// expiries (a servo that stopped by itself: the daemon died or stalled). Faults, from START_S
// seconds after start: silence, crc (corrupt CRC), hwerror (overload bit), slow (20 ms replies).

#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "swivel/cli/command_line.hpp"
#include "swivel/clock.hpp"
#include "swivel/dynamixel/bus.hpp"
#include "swivel/dynamixel/emulator.hpp"

namespace {

volatile sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

struct Fault {
  std::string kind;
  std::uint8_t id = 0;
  double start_s = 0.0;
  bool applied = false;
};

int usage() {
  std::fputs(
      "usage: swivel-dxl-emulator --ids 1,2 [--baud N] [--link PATH] "
      "[--fault silence|crc|hwerror|slow:ID:START_S ...]\n",
      stderr);
  return swivel::cli::kUsageError;
}

// Whole-string numbers: "1x" or "" is not a number.
bool parse_int(const std::string& text, long& out) {
  char* end = nullptr;
  errno = 0;
  out = std::strtol(text.c_str(), &end, 10);
  return !text.empty() && errno == 0 && end == text.c_str() + text.size();
}
bool parse_double(const std::string& text, double& out) {
  char* end = nullptr;
  errno = 0;
  out = std::strtod(text.c_str(), &end);
  return !text.empty() && errno == 0 && end == text.c_str() + text.size();
}

int run(int argc, char** argv) {
  CLI::App app{"swivel-dxl-emulator: a DYNAMIXEL X-series bus on a pseudo-terminal"};
  swivel::dynamixel::Emulator::Options options;
  options.ids.clear();
  std::string ids;
  std::string link;
  std::vector<std::string> fault_args;
  app.add_option("--ids", ids, "servo IDs, comma-separated, e.g. 1,2")->required();
  app.add_option("--baud", options.baud, "baud rate")->capture_default_str();
  app.add_option("--link", link, "make PATH a symbolic link to the device");
  app.add_option("--fault", fault_args,
                 "KIND:ID:START_S (silence, crc, hwerror, slow), repeatable");
  if (const auto exit = swivel::cli::parse(app, argc, argv, "swivel-dxl-emulator")) return *exit;
  for (std::size_t at = 0; at < ids.size();) {
    const std::size_t comma = ids.find(',', at);
    const std::string item = ids.substr(at, comma - at);
    long id = -1;
    if (!parse_int(item, id) || id < 0 || id > swivel::dynamixel::kMaxId) return usage();
    options.ids.push_back(static_cast<std::uint8_t>(id));
    at = comma == std::string::npos ? ids.size() : comma + 1;
  }
  std::vector<Fault> faults;
  for (const std::string& value : fault_args) {
    Fault f;
    const std::size_t a = value.find(':');
    const std::size_t b = a == std::string::npos ? a : value.find(':', a + 1);
    if (b == std::string::npos) return usage();
    f.kind = value.substr(0, a);
    long id = -1;
    if (!parse_int(value.substr(a + 1, b - a - 1), id) || id < 0 ||
        id > swivel::dynamixel::kMaxId || !parse_double(value.substr(b + 1), f.start_s)) {
      return usage();
    }
    f.id = static_cast<std::uint8_t>(id);
    if (f.kind != "silence" && f.kind != "crc" && f.kind != "hwerror" && f.kind != "slow") {
      return usage();
    }
    faults.push_back(f);
  }
  if (options.ids.empty()) return usage();
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  try {
    swivel::dynamixel::Emulator emulator(options);
    if (!link.empty()) {
      std::filesystem::remove(link);
      std::filesystem::create_symlink(emulator.port(), link);
    }
    std::printf("%s\n", emulator.port().c_str());
    std::fflush(stdout);
    const double start_s = swivel::monotonic_s();
    while (g_stop == 0) {
      usleep(10000);
      const double t = swivel::monotonic_s() - start_s;
      for (Fault& f : faults) {
        if (f.applied || t < f.start_s) continue;
        f.applied = true;
        if (f.kind == "silence") emulator.set_silent(f.id, true);
        if (f.kind == "crc") emulator.set_corrupt_crc(f.id, true);
        if (f.kind == "hwerror") {
          emulator.set_hardware_error(f.id, swivel::dynamixel::hardware_error::kOverload);
        }
        if (f.kind == "slow") emulator.set_reply_delay(f.id, 0.02);
        std::fprintf(stderr, "fault %s on ID %u at %.2f s\n", f.kind.c_str(), f.id, t);
      }
    }
    for (const auto& w : emulator.torque_writes()) {
      std::printf("torque_enable id=%u value=%u t=%.3f\n", w.id, w.value, w.time_s - start_s);
    }
    for (const auto& e : emulator.watchdog_expiries()) {
      std::printf("bus_watchdog_expired id=%u t=%.3f\n", e.id, e.time_s - start_s);
    }
    if (!link.empty()) std::filesystem::remove(link);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swivel-dxl-emulator: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // What escapes run() (argument parsing, the options' strings) still ends with a message.
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swivel-dxl-emulator: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "swivel-dxl-emulator: unknown exception\n");
  }
  return 1;
}
