// SPDX-License-Identifier: Apache-2.0
#include "swivel/run_import/run_import.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "swivel/config/config_error.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::run_import {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::string source_dir() {
  const char* env = std::getenv("SWIVEL_SOURCE_DIR");
  return env != nullptr ? env : SWIVEL_SOURCE_DIR_FALLBACK;
}

// A differential map without a header row: t, left, right, x, y, yaw.
constexpr const char* kMap = R"(robot: bench
drivetrain: differential
input: {header_row: false}
time: {index: 0, unit: s}
wheels:
  left: {index: 1, mode: counts_per_row, counts_per_rev: 2796.8}
  right: {index: 2, mode: counts_per_row, counts_per_rev: 2796.8, sign: -1}
truth:
  x: {index: 3, unit: mm}
  y: {index: 4, unit: mm}
  yaw: {index: 5, unit: deg}
)";

std::string map_error(const std::string& text) {
  try {
    parse_import_map(text, "map.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

RunLog import_text(const std::string& map_text, const std::string& csv,
                   ImportSummary* summary = nullptr) {
  const ImportMap map = parse_import_map(map_text, "map.yaml");
  std::istringstream in(csv);
  return import_run(in, "lab.csv", map, summary);
}

std::string import_error(const std::string& map_text, const std::string& csv) {
  try {
    import_text(map_text, csv);
  } catch (const ImportError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << csv;
  return "";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST(ImportMap, UnknownKeysAreRejectedWithTheKeyNamed) {
  EXPECT_EQ(map_error(std::string(kMap) + "colour: red\n"),
            "map.yaml:12:1: colour: unknown key (known: robot, "
            "drivetrain, modules, input, time, wheels, steering, "
            "truth, gyro, commands)");
}

TEST(ImportMap, BadValuesNameFileLineAndKey) {
  EXPECT_EQ(map_error(replaced(kMap, ", sign: -1", ", sign: 2")),
            "map.yaml:7:67: wheels.right.sign: expected 1 or -1, got 2");
  EXPECT_EQ(map_error(replaced(kMap, "counts_per_rev: 2796.8}", "counts_per_rev: 0}")),
            "map.yaml:6:42: wheels.left.counts_per_rev: expected a positive number, got 0");
  EXPECT_EQ(map_error(replaced(kMap, "mode: counts_per_row, counts_per_rev: 2796.8}",
                               "mode: counts_per_row, unit: deg}")),
            "map.yaml:6:42: wheels.left.unit: applies to mode cumulative_angle only (this wheel "
            "counts encoder counts; give its 'counts_per_rev')");
  EXPECT_EQ(
      map_error(replaced(kMap, "mode: counts_per_row, counts_per_rev: 2796.8}", "mode: turns}")),
      "map.yaml:6:20: wheels.left.mode: expected one of counts_per_row, cumulative_counts, "
      "cumulative_angle, got 'turns'");
  EXPECT_EQ(map_error(replaced(kMap, "{index: 3, unit: mm}", "{index: 3, unit: inch}")),
            "map.yaml:9:17: truth.x.unit: expected one of m, mm, got 'inch'");
  EXPECT_EQ(map_error(replaced(kMap, "{index: 0, unit: s}", "{index: 0, column: t}")),
            "map.yaml:4:7: time: give either 'column' (a header name) or 'index' (0-based), not "
            "both");
  EXPECT_EQ(map_error(replaced(kMap, "{index: 0, unit: s}", "{column: t}")),
            "map.yaml:4:8: time.column: a column by name needs 'input: {header_row: true}'; "
            "without a header row give its 0-based 'index'");
  EXPECT_EQ(map_error(replaced(kMap, "{index: 0, unit: s}", "{index: 0, nominal_period_s: 0.05}")),
            "map.yaml:4:18: time.nominal_period_s: nominal_period_s and real_period_s come "
            "together (the time column's step, and the period actually achieved)");
  EXPECT_EQ(map_error(replaced(kMap, "time: {index: 0, unit: s}\n", "")),
            "map.yaml:1:1: missing required key 'time' (a time column or row_period_s)");
  EXPECT_EQ(map_error(replaced(kMap, "  yaw: {index: 5, unit: deg}\n", "")),
            "map.yaml:9:3: truth: missing required key 'yaw' (the motion-capture x, y and yaw "
            "come together)");
  EXPECT_EQ(map_error(std::string(kMap) + "steering: []\n"),
            "map.yaml:12:1: steering: applies to swpc robots only (this one is differential)");
}

TEST(ImportMap, SwpcNeedsOneWheelAndOneSteeringEntryPerModule) {
  const std::string swpc = R"(robot: cart
drivetrain: swpc
modules: 2
time: {row_period_s: 0.01}
wheels:
  - {index: 0, mode: cumulative_angle, unit: rad}
  - {index: 1, mode: cumulative_angle, unit: rad}
steering:
  - {index: 2, unit: deg}
)";
  EXPECT_EQ(map_error(swpc),
            "map.yaml:8:1: steering: expected a list of 2 entries (modules: 2), one per module");
  const ImportMap m = parse_import_map(swpc + "  - {index: 3, unit: deg, sign: -1}\n", "map.yaml");
  ASSERT_EQ(m.steering.size(), 2U);
  EXPECT_DOUBLE_EQ(m.steering[1].scale, -std::numbers::pi / 180.0);
  EXPECT_EQ(m.module_count, 2U);
}

TEST(Import, CountsPerRowAccumulateWithCountsPerRevAndSign) {
  ImportSummary summary;
  const RunLog log = import_text(kMap,
                                 "0,0,0,0,0,0\n"
                                 "0.05,10,-20,1.5,-2,90\n"
                                 "0.1,5,-5,3,-4,180\n",
                                 &summary);
  ASSERT_EQ(log.samples.size(), 3U);
  const double q = kTwoPi / 2796.8;
  EXPECT_DOUBLE_EQ(log.samples[1].wheel_rad[0], 10 * q);
  EXPECT_DOUBLE_EQ(log.samples[2].wheel_rad[0], 15 * q);
  EXPECT_DOUBLE_EQ(log.samples[2].wheel_rad[1], 25 * q);  // sign -1
  EXPECT_DOUBLE_EQ(log.samples[2].t_s, 0.1);
  ASSERT_TRUE(log.samples[2].has_truth);
  EXPECT_DOUBLE_EQ(log.samples[2].truth.x_m, 0.003);
  EXPECT_DOUBLE_EQ(log.samples[2].truth.y_m, -0.004);
  EXPECT_DOUBLE_EQ(log.samples[2].truth.yaw_rad, std::numbers::pi);
  EXPECT_FALSE(log.samples[0].has_gyro);
  EXPECT_FALSE(log.samples[0].has_cmd);
  EXPECT_EQ(log.header.robot, "bench");
  EXPECT_EQ(log.header.comments[0], "imported from: lab.csv");
  EXPECT_EQ(summary.rows, 3U);
  EXPECT_EQ(summary.truth_rows, 3U);
  EXPECT_EQ(summary.gyro_rows, 0U);
}

TEST(Import, CumulativeCountsAndAnglesKeepTheirOrigin) {
  std::string map = replaced(kMap, "mode: counts_per_row, counts_per_rev: 2796.8}",
                             "mode: cumulative_counts, counts_per_rev: 1000}");
  map = replaced(map, "mode: counts_per_row, counts_per_rev: 2796.8, sign: -1}",
                 "mode: cumulative_angle, unit: deg, sign: -1}");
  const RunLog log = import_text(map, "0,500,90,,,\n0.01,750,-180,,,\n");
  ASSERT_EQ(log.samples.size(), 2U);
  EXPECT_DOUBLE_EQ(log.samples[0].wheel_rad[0], 0.5 * kTwoPi);
  EXPECT_DOUBLE_EQ(log.samples[1].wheel_rad[0], 0.75 * kTwoPi);
  EXPECT_DOUBLE_EQ(log.samples[0].wheel_rad[1], -std::numbers::pi / 2.0);
  EXPECT_DOUBLE_EQ(log.samples[1].wheel_rad[1], std::numbers::pi);
  EXPECT_FALSE(log.samples[0].has_truth);  // empty truth cells: no motion-capture sample
}

TEST(Import, RealRowPeriodOverridesTheNominalTimeColumn) {
  const std::string map =
      replaced(kMap, "{index: 0, unit: s}",
               "{index: 0, unit: ms, nominal_period_s: 0.05, real_period_s: 0.0512}");
  ImportSummary summary;
  const RunLog log = import_text(map,
                                 "1000,0,0,,,\n"
                                 "1050,0,0,,,\n"
                                 "1150,0,0,,,\n",  // a missing row
                                 &summary);
  ASSERT_EQ(log.samples.size(), 3U);
  EXPECT_DOUBLE_EQ(log.samples[0].t_s, 1.0);
  EXPECT_DOUBLE_EQ(log.samples[1].t_s, 1.0 + 0.0512);
  EXPECT_DOUBLE_EQ(log.samples[2].t_s, 1.0 + 3 * 0.0512);
  EXPECT_EQ(summary.gaps, 1U);
  EXPECT_NE(log.header.comments[2].find("real row period of 0.0512 s"), std::string::npos);

  EXPECT_EQ(import_error(map, "1000,0,0,,,\n1080,0,0,,,\n"),
            "lab.csv:2: column 0 [map.yaml: time]: step of 0.08 s is not a whole number of "
            "nominal periods (0.05 s)");
}

TEST(Import, FixedRowPeriodNeedsNoTimeColumn) {
  const std::string map = replaced(kMap, "{index: 0, unit: s}", "{row_period_s: 0.01}");
  const RunLog log = import_text(map, "9,1,1,,,\n9,1,1,,,\n9,1,1,,,\n");
  ASSERT_EQ(log.samples.size(), 3U);
  EXPECT_DOUBLE_EQ(log.samples[2].t_s, 0.02);
  EXPECT_EQ(map_error(replaced(kMap, "{index: 0, unit: s}", "{row_period_s: 0.01, unit: s}")),
            "map.yaml:4:28: time.unit: applies to a time column only (this map has a fixed "
            "row_period_s)");
}

TEST(Import, HeaderNamesDelimiterCommentsGyroAndCommands) {
  const std::string map = R"(robot: bench
drivetrain: differential
input: {header_row: true, delimiter: ";", comment_prefix: "%"}
time: {column: stamp, unit: ms}
wheels:
  left: {column: encL, mode: cumulative_counts, counts_per_rev: 4096}
  right: {column: encR, mode: cumulative_counts, counts_per_rev: 4096}
gyro: {column: gz, unit: deg/s, sign: -1}
commands:
  vx: {column: v, unit: mm/s}
  wz: {column: w, unit: rad/s}
)";
  const std::string csv =
      "% exported by the bench logger\n"
      "w;v;stamp;encR;encL;gz\n"
      "0.5;100;0;0;0;90\n"
      ";;10;4096;2048;\n"
      "0.1;200;20;4096;2048;NaN\n";
  const RunLog log = import_text(map, csv);
  ASSERT_EQ(log.samples.size(), 3U);
  EXPECT_DOUBLE_EQ(log.samples[1].t_s, 0.01);
  EXPECT_DOUBLE_EQ(log.samples[1].wheel_rad[0], std::numbers::pi);
  EXPECT_DOUBLE_EQ(log.samples[1].wheel_rad[1], kTwoPi);
  EXPECT_TRUE(log.samples[0].has_gyro);
  EXPECT_DOUBLE_EQ(log.samples[0].gyro_wz_radps, -std::numbers::pi / 2.0);
  EXPECT_FALSE(log.samples[1].has_gyro);
  EXPECT_FALSE(log.samples[2].has_gyro);  // NaN: no sample
  EXPECT_TRUE(log.samples[0].has_cmd);
  EXPECT_DOUBLE_EQ(log.samples[0].cmd.vx_mps, 0.1);
  EXPECT_DOUBLE_EQ(log.samples[0].cmd.vy_mps, 0.0);
  EXPECT_DOUBLE_EQ(log.samples[0].cmd.wz_radps, 0.5);
  EXPECT_FALSE(log.samples[1].has_cmd);

  EXPECT_EQ(import_error(map, "w;v;stamp;encR;encLeft;gz\n"),
            "lab.csv:1: header row has no column 'encL' [map.yaml: wheels.left]");
  EXPECT_EQ(import_error(map, "w;v;stamp;encR;encL;gz\n0.5;;0;0;0;90\n"),
            "lab.csv:2: column v (index 1) [map.yaml: commands.vx]: empty, but the command "
            "columns must be all present or all empty");
}

TEST(Import, TabDelimitedFilesKeepTheirEmptyCells) {
  const std::string map = replaced(kMap, "input: {header_row: false}",
                                   R"(input: {header_row: false, delimiter: "\t"})");
  const RunLog log = import_text(map, "0\t1\t2\t\t\t\n0.1\t3\t4\t5\t6\t7\n");
  ASSERT_EQ(log.samples.size(), 2U);
  EXPECT_FALSE(log.samples[0].has_truth);
  EXPECT_DOUBLE_EQ(log.samples[1].wheel_rad[0], 4 * kTwoPi / 2796.8);
  EXPECT_DOUBLE_EQ(log.samples[1].truth.x_m, 0.005);
  EXPECT_EQ(map_error(replaced(kMap, "input: {header_row: false}", "input: {delimiter: \";;\"}")),
            "map.yaml:3:9: input.delimiter: expected one character (or \"\\t\"), got ';;'");
}

TEST(Import, MalformedLinesNameFileLineAndColumn) {
  EXPECT_EQ(import_error(kMap, "0,0,0,0,0,0\n0.05,1,x,0,0,0\n"),
            "lab.csv:2: column 2 [map.yaml: wheels.right]: expected a finite number, got 'x'");
  EXPECT_EQ(import_error(kMap, "0,0,0,0,0,0\n\n0.05,1,1,0\n"),
            "lab.csv:3: expected at least 6 columns, got 4");
  EXPECT_EQ(import_error(kMap, "0,0,0,0,,0\n"),
            "lab.csv:1: column 4 [map.yaml: truth.y]: empty, but the motion-capture x, y and "
            "yaw must be all present or all empty");
  EXPECT_EQ(import_error(kMap, "1,0,0,,,\n0.5,0,0,,,\n"),
            "lab.csv:2: column 0 [map.yaml: time]: time goes backwards (0.5 after 1)");
  EXPECT_EQ(import_error(kMap, "0,nan,0,,,\n"),
            "lab.csv:1: column 1 [map.yaml: wheels.left]: expected a finite number, got 'nan'");
  EXPECT_EQ(import_error(kMap, ""), "lab.csv:1: no data rows");
}

// Reads the vendored OptiOdom run the plain way: rows of t, x, y, yaw, counts right, left.
std::vector<std::vector<double>> read_plain_csv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<double> row;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

TEST(Import, OptiOdomRunMatchesItsCountsAndTruth) {
  const std::string dir = source_dir();
  const ImportMap map = load_import_map(dir + "/config/import/optiodom_diff.yaml");
  const RobotModel model = load_robot_model(dir + "/config/robots/optiodom_diff.yaml");
  EXPECT_NO_THROW(check_map_matches_model(map, model));
  EXPECT_EQ(model.sensors.wheel_encoder_counts_per_rev, 43.7 * 64);

  const std::string run = dir + "/tests/data/optiodom/231220200157_run-01.csv";
  const std::vector<std::vector<double>> rows = read_plain_csv(run);
  ASSERT_GT(rows.size(), 500U);
  const std::string out =
      (std::filesystem::temp_directory_path() / "swivel_import_optiodom.csv").string();
  const ImportSummary summary = import_file(map, run, out);
  const RunLog log = read_run_log(out);
  std::filesystem::remove(out);
  ASSERT_EQ(log.samples.size(), rows.size());
  EXPECT_EQ(summary.rows, rows.size());
  EXPECT_EQ(log.header.robot, "optiodom_diff");
  EXPECT_EQ(log.header.comments.front(), "imported from: " + run);

  // Wheel angle after N rows: the sum of the counts x 2 pi / (43.7 x 64); right is column 4.
  double right = 0.0;
  double left = 0.0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    right += rows[k][4];
    left += rows[k][5];
    const RunLogSample& s = log.samples[k];
    ASSERT_NEAR(s.wheel_rad[1], right * kTwoPi / 2796.8, 1e-9) << "row " << k;
    ASSERT_NEAR(s.wheel_rad[0], left * kTwoPi / 2796.8, 1e-9) << "row " << k;
    ASSERT_TRUE(s.has_truth);
    EXPECT_EQ(s.truth.x_m, rows[k][1]);
    EXPECT_EQ(s.truth.y_m, rows[k][2]);
    EXPECT_EQ(s.truth.yaw_rad, rows[k][3]);
    EXPECT_FALSE(s.has_gyro);
    EXPECT_FALSE(s.has_cmd);
    // Time: the nominal 0.05 s column rescaled to the real period.
    EXPECT_NEAR(s.t_s, rows[k][0] * *map.real_period_s / 0.05, 1e-9);
  }
  EXPECT_GT(std::abs(right), 1000.0);  // the robot drove
}

TEST(Import, ShippedMapRefusesAModelOfAnotherRobot) {
  const std::string dir = source_dir();
  const ImportMap map = load_import_map(dir + "/config/import/optiodom_diff.yaml");
  const RobotModel docent = load_robot_model(dir + "/config/robots/docent.yaml");
  try {
    check_map_matches_model(map, docent);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("robot 'optiodom_diff' but the model is 'docent'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace swivel::run_import
