// SPDX-License-Identifier: Apache-2.0
// CSV text -> parse_run_log. Contract: a log or RunLogError, nothing else. A log that parses
// must survive RunLogWriter and read back to the same values (the writer promises numbers
// in the shortest form that reads back to the same double).

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "fuzz_support.hpp"
#include "swivel/run_log.hpp"

namespace {

constexpr const char* kTarget = "fuzz_run_log";

bool same(const swivel::RunLogSample& a, const swivel::RunLogSample& b, std::size_t modules,
          bool swpc, bool estimate) {
  if (estimate && (a.estimate.x_m != b.estimate.x_m || a.estimate.y_m != b.estimate.y_m ||
                   a.estimate.yaw_rad != b.estimate.yaw_rad || a.fault_code != b.fault_code)) {
    return false;
  }
  if (a.t_s != b.t_s || a.cmd.vx_mps != b.cmd.vx_mps || a.cmd.vy_mps != b.cmd.vy_mps ||
      a.cmd.wz_radps != b.cmd.wz_radps || a.gyro_wz_radps != b.gyro_wz_radps ||
      a.has_truth != b.has_truth || a.has_gyro != b.has_gyro || a.has_cmd != b.has_cmd) {
    return false;
  }
  for (std::size_t i = 0; i < modules; ++i) {
    if (a.wheel_rad[i] != b.wheel_rad[i]) return false;
    if (swpc && a.steer_rad[i] != b.steer_rad[i]) return false;
  }
  return !a.has_truth || (a.truth.x_m == b.truth.x_m && a.truth.y_m == b.truth.y_m &&
                          a.truth.yaw_rad == b.truth.yaw_rad);
}

}  // namespace

// The entry point libFuzzer names.
// NOLINTNEXTLINE(readability-identifier-naming)
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  swivel::RunLog log;
  try {
    log = swivel::parse_run_log(in, "fuzz.csv");
  } catch (const swivel::RunLogError&) {
    return 0;
  } catch (const std::exception& e) {
    swivel::fuzz::unexpected_exception(kTarget, e);
  }

  std::ostringstream out;
  swivel::RunLog again;
  try {
    swivel::RunLogWriter writer(out, log.header);
    for (const auto& sample : log.samples) writer.write(sample);
    writer.flush();
    std::istringstream back(out.str());
    again = swivel::parse_run_log(back, "written.csv");
  } catch (const std::exception& e) {
    swivel::fuzz::contract_broken(
        kTarget, "a log that parsed does not write and read back: " + std::string(e.what()) +
                     "\n--- written:\n" + out.str());
  }
  const auto& h = log.header;
  const bool swpc = h.drivetrain == swivel::DrivetrainKind::kSwpc;
  bool ok = again.header.robot == h.robot && again.header.drivetrain == h.drivetrain &&
            again.header.module_count == h.module_count &&
            again.header.estimate_columns == h.estimate_columns &&
            again.header.gyro_mean_over_row == h.gyro_mean_over_row &&
            again.samples.size() == log.samples.size();
  for (std::size_t i = 0; ok && i < log.samples.size(); ++i) {
    ok = same(log.samples[i], again.samples[i], h.module_count, swpc, h.estimate_columns);
  }
  if (!ok) {
    swivel::fuzz::contract_broken(kTarget,
                                  "RunLogWriter changed the log\n--- written:\n" + out.str());
  }
  return 0;
}
