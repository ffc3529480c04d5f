// SPDX-License-Identifier: Apache-2.0
// `swivel-lab reproduce square --short`: calibrated parameters must track the square better
// than the design values, the statistics and both plots must be written, and the figures
// must not depend on how many jobs ran them. One short lap per direction lets slip and
// scrub of the default size outweigh the systematic errors in some seeds, so the tests use
// a fifth of them: what they check is the systematic part.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace swivel {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kShort =
    " reproduce square --short --seed 3 --slip-std 0.002 --scrub-std 0.001";

// NOLINTNEXTLINE(bugprone-exception-escape): seen in nlohmann::json's own destructor
struct SquareRun {
  int status = -1;
  std::string out;
  json results;
};

// Runs the tool with `args` into a fresh folder named after `name`, and removes it again.
SquareRun run_square(const std::string& name, const std::string& args) {
  const fs::path dir =
      fs::temp_directory_path() / ("swivel_lab_square_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string log = dir.string() + ".log";
  const std::string cmd =
      std::string(SWIVEL_LAB_EXE) + args + " --out " + dir.string() + " >" + log + " 2>&1";
  SquareRun run;
  // The shell redirects the tool's output. NOLINTNEXTLINE(cert-env33-c)
  const int status = std::system(cmd.c_str());
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::stringstream text;
  text << std::ifstream(log).rdbuf();
  run.out = text.str();
  std::ifstream in(dir / "results.json");
  if (in.good()) run.results = json::parse(in);
  for (const char* png : {"square.png", "square_spread.png"}) {
    if (!fs::exists(dir / png) || fs::file_size(dir / png) < 1000) run.status = 100;
  }
  fs::remove_all(dir);
  fs::remove(log);
  return run;
}

double measured(const json& j, const std::string& what, const std::string& model) {
  return j.at("measured").at(what).at(model).get<double>();
}

TEST(LabReproduceSquareTest, ShortModeCalibratedErrorBelowNominalWithItsStatistics) {
  const SquareRun run = run_square("short", std::string(kShort) + " --jobs 1");
  ASSERT_EQ(run.status, 0) << run.out;
  const json& j = run.results;
  for (const char* what : {"position_mae_m", "heading_mae_deg"}) {
    EXPECT_LT(measured(j, what, "calibrated"), measured(j, what, "nominal")) << what;
    EXPECT_LT(measured(j, what, "exact"), measured(j, what, "nominal")) << what;
  }
  for (const char* what : {"position_mae_standard_error_m", "heading_mae_standard_error_deg"}) {
    EXPECT_GT(measured(j, what, "nominal"), 0.0) << what;
    EXPECT_GT(measured(j, what, "calibrated"), 0.0) << what;
  }
  // Two calibrations, each tracked twice per direction (--short), like the two references.
  ASSERT_EQ(j.at("calibrations").size(), 2U);
  for (const json& c : j.at("calibrations")) {
    EXPECT_EQ(c.at("runs").size(), 4U);
    EXPECT_EQ(c.at("modules").size(), 4U);
    EXPECT_NE(c.at("calibration_seed").get<std::uint64_t>(), 0U);
  }
  EXPECT_NE(j["calibrations"][0]["calibration_seed"], j["calibrations"][1]["calibration_seed"]);
  EXPECT_EQ(j.at("nominal_runs").size(), 4U);
  EXPECT_EQ(j.at("exact_runs").size(), 4U);
  const json& spread = j.at("measured").at("position_change_spread_percent");
  EXPECT_EQ(spread.at("count").get<int>(), 2);
  EXPECT_LE(spread.at("min").get<double>(), spread.at("max").get<double>());
  // The mean change is the mean over the seeds' models against the design values.
  const double mean_change =
      j.at("measured").at("position_change_percent").at("mean").get<double>();
  EXPECT_NEAR(mean_change,
              100.0 * (measured(j, "position_mae_m", "calibrated") /
                           measured(j, "position_mae_m", "nominal") -
                       1.0),
              1e-9);
  // Printed next to the paper's figures, with the spread and the bound.
  EXPECT_NE(run.out.find("-64.60 %"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("-80.15 %"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find(" +- "), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("change per calibration seed (2 seeds)"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("true values as the model"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("[4/4]"), std::string::npos) << "progress\n" << run.out;
}

TEST(LabReproduceSquareTest, FiguresDoNotDependOnTheNumberOfJobs) {
  const SquareRun one = run_square("jobs1", std::string(kShort) + " --jobs 1");
  const SquareRun three = run_square("jobs3", std::string(kShort) + " --jobs 3");
  ASSERT_EQ(one.status, 0) << one.out;
  ASSERT_EQ(three.status, 0) << three.out;
  EXPECT_EQ(one.results.at("measured"), three.results.at("measured"));
  EXPECT_EQ(one.results.at("calibrations"), three.results.at("calibrations"));
}

// --calibrated-model tracks with a model file (e.g. the one swiveld wrote) instead of the
// simulated calibrations: the true model itself must beat the design values.
TEST(LabReproduceSquareTest, CalibratedModelFileIsTheOneTracked) {
  const char* env = std::getenv("SWIVEL_SOURCE_DIR");
  const std::string source = env != nullptr ? env : SWIVEL_SOURCE_DIR_FALLBACK;
  const std::string model = source + "/config/robots/swpc4_table4.yaml";
  const SquareRun run = run_square("model", std::string(kShort) + " --calibrated-model " + model);
  ASSERT_EQ(run.status, 0) << run.out;
  const json& j = run.results;
  EXPECT_EQ(j.at("calibrated_model").get<std::string>(), model);
  EXPECT_EQ(j.at("settings").at("calibration_seeds").get<int>(), 0);
  ASSERT_EQ(j.at("calibrations").size(), 1U);
  EXPECT_EQ(j["calibrations"][0].at("calibration_seed").get<int>(), 0);
  EXPECT_LT(measured(j, "position_mae_m", "calibrated"),
            0.5 * measured(j, "position_mae_m", "nominal"));
  EXPECT_LT(measured(j, "heading_mae_deg", "calibrated"),
            0.5 * measured(j, "heading_mae_deg", "nominal"));
}

}  // namespace
}  // namespace swivel
