// SPDX-License-Identifier: Apache-2.0
// main() of the Google Benchmark executables (swivel-bench-swpc, -localization,
// -calibration): BENCHMARK_MAIN() plus `--version`, and exit code 2 on an unknown argument.

#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

#include "swivel/cli/command_line.hpp"
#include "swivel/version.hpp"

int main(int argc, char** argv) {
  const std::string program =
      argc > 0 ? std::filesystem::path(argv[0]).filename().string() : "swivel-bench";
  for (int i = 1; i < argc; ++i) {
    if (std::string_view(argv[i]) == "--version") {
      std::printf("%s\n", swivel::version_line(program).c_str());
      return 0;
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return swivel::cli::kUsageError;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
