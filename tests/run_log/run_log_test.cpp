// SPDX-License-Identifier: Apache-2.0
#include "swivel/run_log.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <sstream>
#include <string>

namespace swivel {
namespace {

RunLogHeader swpc_header(std::size_t n) {
  RunLogHeader h;
  h.robot = "swpc4";
  h.drivetrain = DrivetrainKind::kSwpc;
  h.module_count = n;
  return h;
}

std::string expect_error(const std::string& text) {
  std::istringstream in(text);
  try {
    parse_run_log(in, "run.csv");
  } catch (const RunLogError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

constexpr const char* kDifferentialHead =
    "# swivel-run 1\n# robot: docent\n# drivetrain: differential\n"
    "t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw\n";

TEST(RunLog, ColumnsFollowTheDesign) {
  RunLogHeader diff;
  EXPECT_EQ(run_log_columns(diff).size(), 10U);
  const auto swpc = run_log_columns(swpc_header(4));
  ASSERT_EQ(swpc.size(), 16U);
  EXPECT_EQ(swpc[4], "steer_1");
  EXPECT_EQ(swpc[7], "steer_4");
  EXPECT_EQ(swpc[8], "wheel_1");
  EXPECT_EQ(swpc[12], "gyro_wz");
  EXPECT_EQ(swpc[15], "truth_yaw");
}

TEST(RunLog, SwpcRoundTripIsExact) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "swivel_run_log_roundtrip.csv").string();
  std::vector<RunLogSample> written;
  {
    RunLogWriter writer(path, swpc_header(3));
    for (int k = 0; k < 50; ++k) {
      RunLogSample s;
      s.t_s = 0.01 * k;
      s.cmd = Twist2{0.1 + k * 1e-3, -0.2, 1.0 / 3.0};
      for (std::size_t i = 0; i < 3; ++i) {
        s.steer_rad[i] = std::sin(0.1 * k + static_cast<double>(i));
        s.wheel_rad[i] = 1e-7 * k * k - static_cast<double>(i);
      }
      s.gyro_wz_radps = std::exp(-0.3 * k);
      s.has_truth = k % 3 == 0;
      if (s.has_truth) s.truth = Pose2{k * 0.1234567890123, -k * 1e-9, 3.0 - 0.01 * k};
      writer.write(s);
      written.push_back(s);
    }
    writer.flush();
  }
  const RunLog log = read_run_log(path);
  EXPECT_EQ(log.header.robot, "swpc4");
  EXPECT_EQ(log.header.drivetrain, DrivetrainKind::kSwpc);
  EXPECT_EQ(log.header.module_count, 3U);
  ASSERT_EQ(log.samples.size(), written.size());
  for (std::size_t k = 0; k < written.size(); ++k) {
    const RunLogSample& a = written[k];
    const RunLogSample& b = log.samples[k];
    EXPECT_EQ(a.t_s, b.t_s);
    EXPECT_EQ(a.cmd.vx_mps, b.cmd.vx_mps);
    EXPECT_EQ(a.cmd.wz_radps, b.cmd.wz_radps);
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_EQ(a.steer_rad[i], b.steer_rad[i]);
      EXPECT_EQ(a.wheel_rad[i], b.wheel_rad[i]);
    }
    EXPECT_EQ(a.gyro_wz_radps, b.gyro_wz_radps);
    ASSERT_EQ(a.has_truth, b.has_truth);
    if (a.has_truth) {
      EXPECT_EQ(a.truth.x_m, b.truth.x_m);
      EXPECT_EQ(a.truth.y_m, b.truth.y_m);
      EXPECT_EQ(a.truth.yaw_rad, b.truth.yaw_rad);
    }
  }
  std::filesystem::remove(path);
}

TEST(RunLog, DifferentialRowsWithoutTruthHaveEmptyCells) {
  std::ostringstream out;
  RunLogWriter writer(out, RunLogHeader{"docent", DrivetrainKind::kDifferential, 2, {}, false});
  RunLogSample s;
  s.t_s = 0.5;
  s.wheel_rad[0] = 1.5;
  s.wheel_rad[1] = -2.0;
  writer.write(s);
  EXPECT_EQ(out.str(), std::string(kDifferentialHead) + "0.5,0,0,0,1.5,-2,0,,,\n");
  std::istringstream in(out.str());
  const RunLog log = parse_run_log(in, "mem");
  ASSERT_EQ(log.samples.size(), 1U);
  EXPECT_FALSE(log.samples[0].has_truth);
  EXPECT_EQ(log.samples[0].wheel_rad[1], -2.0);
}

TEST(RunLog, UnknownCommentsAndBlankLinesAreIgnored) {
  const std::string text =
      "# swivel-run 1\n# recorded by: bench 3\n# robot: docent\n# drivetrain: differential\n"
      "# note: carpet\n"
      "t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw\n"
      "0,0,0,0,0,0,0,1,2,3\n\n# pause\n0.01,0.1,0,0,0.1,0.1,0.001,,,\n";
  std::istringstream in(text);
  const RunLog log = parse_run_log(in, "run.csv");
  ASSERT_EQ(log.samples.size(), 2U);
  EXPECT_TRUE(log.samples[0].has_truth);
  EXPECT_EQ(log.samples[0].truth.yaw_rad, 3.0);
  EXPECT_EQ(log.samples[1].gyro_wz_radps, 0.001);
  EXPECT_EQ(log.header.comments,
            (std::vector<std::string>{"recorded by: bench 3", "note: carpet"}));
}

TEST(RunLog, HeaderKeysDoNotDependOnTheBlanksAfterTheHash) {
  // An annotation is written back as "# <text>": were "#swivel-run 2" an annotation, the
  // copy would read as a version line (found by fuzz_run_log).
  EXPECT_EQ(expect_error("# swivel-run 1\n#swivel-run 2\n# robot: docent\n"),
            "run.csv:2: unsupported run log version 2 (this reader reads 1)");
  const std::string text =
      "#swivel-run 1\n#robot:docent\n#\tdrivetrain: differential\n#swivel-runner\n"
      "t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw\n";
  std::istringstream in(text);
  const RunLog log = parse_run_log(in, "run.csv");
  EXPECT_EQ(log.header.robot, "docent");
  EXPECT_EQ(log.header.comments, (std::vector<std::string>{"swivel-runner"}));
}

TEST(RunLog, WrongColumnCountNamesTheLine) {
  std::string text = kDifferentialHead;
  for (int k = 0; k < 52; ++k) text += std::to_string(k) + ",0,0,0,0,0,0,,,\n";
  text += "52,0,0,0,0,0,,,\n";  // line 57: one column missing
  EXPECT_EQ(expect_error(text), "run.csv:57: expected 10 columns, got 9");
}

TEST(RunLog, SwpcColumnCountComesFromModules) {
  const std::string text =
      "# swivel-run 1\n# robot: swpc4\n# drivetrain: swpc\n# modules: 4\n"
      "t,cmd_vx,cmd_vy,cmd_wz,steer_1,steer_2,steer_3,steer_4,wheel_1,wheel_2,wheel_3,wheel_4,"
      "gyro_wz,truth_x,truth_y,truth_yaw\n"
      "0,0,0,0,0,0,0,0,0,0,0,0,0,,\n";
  EXPECT_EQ(expect_error(text), "run.csv:6: expected 16 columns, got 15");
}

TEST(RunLog, NonNumberNamesLineAndColumn) {
  const std::string text =
      std::string(kDifferentialHead) + "0,0,0,0,0,0,0,,,\n0.01,0,0,0,abc,0,0,,,\n";
  EXPECT_EQ(expect_error(text), "run.csv:6: column wheel_l: expected a finite number, got 'abc'");
  const std::string nan_text = std::string(kDifferentialHead) + "0,0,0,0,0,0,nan,,,\n";
  EXPECT_EQ(expect_error(nan_text),
            "run.csv:5: column gyro_wz: expected a finite number, got 'nan'");
}

TEST(RunLog, MissingHeaderRowIsReported) {
  const std::string text =
      "# swivel-run 1\n# robot: docent\n# drivetrain: differential\n0,0,0,0,0,0,0,,,\n";
  EXPECT_EQ(expect_error(text),
            "run.csv:4: expected header row "
            "'t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw' "
            "(optionally followed by ',est_x,est_y,est_yaw,fault'), got '0,0,0,0,0,0,0,,,'");
  EXPECT_EQ(expect_error("# swivel-run 1\n# drivetrain: differential\n"),
            "run.csv:2: missing header row "
            "'t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw'");
}

TEST(RunLog, MissingOrWrongPreambleIsReported) {
  EXPECT_EQ(expect_error("# robot: x\n# drivetrain: differential\nt\n"),
            "run.csv:3: missing '# swivel-run 1' line");
  EXPECT_EQ(expect_error("# swivel-run 2\n"),
            "run.csv:1: unsupported run log version 2 (this reader reads 1)");
  EXPECT_EQ(expect_error("# swivel-run 1\n# drivetrain: tank\n"),
            "run.csv:2: expected drivetrain 'differential' or 'swpc', got 'tank'");
  EXPECT_EQ(expect_error("# swivel-run 1\n# drivetrain: swpc\nt\n"),
            "run.csv:3: missing '# modules: N' line (required for an swpc run log)");
  EXPECT_EQ(expect_error(""), "run.csv:1: missing '# swivel-run 1' line");
}

TEST(RunLog, PartialTruthAndBackwardTimeAreRejected) {
  EXPECT_EQ(expect_error(std::string(kDifferentialHead) + "0,0,0,0,0,0,0,1,,\n"),
            "run.csv:5: truth_x, truth_y and truth_yaw must be all present or all empty");
  EXPECT_EQ(expect_error(std::string(kDifferentialHead) + "1,0,0,0,0,0,0,,,\n0.5,0,0,0,0,0,0,,,\n"),
            "run.csv:6: time goes backwards (0.5 after 1)");
}

TEST(RunLog, TruncatedLastLineIsReported) {
  const std::string text = std::string(kDifferentialHead) + "0,0,0,0,0,0,0,,,\n0.01,0,0,0,0.";
  EXPECT_EQ(expect_error(text), "run.csv:6: expected 10 columns, got 5");
}

TEST(RunLog, EstimateColumnsRoundTripExactly) {
  RunLogHeader header;
  header.robot = "docent";
  header.estimate_columns = true;
  const auto columns = run_log_columns(header);
  ASSERT_EQ(columns.size(), 14U);
  EXPECT_EQ(columns[10], "est_x");
  EXPECT_EQ(columns[13], "fault");

  std::ostringstream out;
  std::vector<RunLogSample> written;
  {
    RunLogWriter writer(out, header);
    for (int k = 0; k < 20; ++k) {
      RunLogSample s;
      s.t_s = 0.01 * k;
      s.cmd = Twist2{0.3, 0.0, 0.1 * k};
      s.wheel_rad = {0.1 * k, 0.2 * k};
      s.gyro_wz_radps = 1.0 / 7.0;
      s.has_truth = k % 2 == 0;
      if (s.has_truth) s.truth = Pose2{0.003 * k, -1e-5 * k, 0.5};
      s.estimate = Pose2{0.0031 * k, 1.0 / 3.0, -0.25 * k};
      s.fault_code = static_cast<std::uint16_t>(k == 7 ? 65535 : k % 3);
      writer.write(s);
      written.push_back(s);
    }
  }
  EXPECT_NE(out.str().find(",truth_yaw,est_x,est_y,est_yaw,fault\n"), std::string::npos);
  EXPECT_NE(out.str().find(",,,0.0031,0.3333333333333333,-0.25,1\n"), std::string::npos)
      << "a row without truth keeps its three empty cells before the estimate";
  std::istringstream in(out.str());
  const RunLog log = parse_run_log(in, "mem");
  EXPECT_TRUE(log.header.estimate_columns);
  ASSERT_EQ(log.samples.size(), written.size());
  for (std::size_t k = 0; k < written.size(); ++k) {
    const RunLogSample& a = written[k];
    const RunLogSample& b = log.samples[k];
    EXPECT_EQ(a.t_s, b.t_s);
    EXPECT_EQ(a.wheel_rad[1], b.wheel_rad[1]);
    ASSERT_EQ(a.has_truth, b.has_truth);
    if (a.has_truth) {
      EXPECT_EQ(a.truth.x_m, b.truth.x_m);
    }
    EXPECT_EQ(a.estimate.x_m, b.estimate.x_m);
    EXPECT_EQ(a.estimate.y_m, b.estimate.y_m);
    EXPECT_EQ(a.estimate.yaw_rad, b.estimate.yaw_rad);
    EXPECT_EQ(a.fault_code, b.fault_code);
  }
}

TEST(RunLog, LogsWithoutEstimateColumnsStillReadAndAreWrittenWithout) {
  std::istringstream in(std::string(kDifferentialHead) + "0,0.1,0,0,1,2,0,3,4,5\n");
  const RunLog log = parse_run_log(in, "old.csv");
  EXPECT_FALSE(log.header.estimate_columns);
  ASSERT_EQ(log.samples.size(), 1U);
  EXPECT_EQ(log.samples[0].truth.yaw_rad, 5.0);
  EXPECT_EQ(log.samples[0].fault_code, 0);

  // Not asked for: the writer leaves them out even when a sample carries an estimate.
  std::ostringstream out;
  RunLogWriter writer(out, log.header);
  RunLogSample s = log.samples[0];
  s.estimate = Pose2{1.0, 2.0, 3.0};
  s.fault_code = 4;
  writer.write(s);
  EXPECT_EQ(out.str(), std::string(kDifferentialHead) + "0,0.1,0,0,1,2,0,3,4,5\n");
}

TEST(RunLog, BadEstimateColumnsAreReported) {
  const std::string head =
      "# swivel-run 1\n# robot: docent\n# drivetrain: differential\n"
      "t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw,est_x,est_y,"
      "est_yaw,fault\n";
  EXPECT_EQ(expect_error(head + "0,0,0,0,0,0,0,,,,1,2,3,1.5\n"),
            "run.csv:5: column fault: expected a fault code (an integer in [0, 65535]), got '1.5'");
  EXPECT_EQ(expect_error(head + "0,0,0,0,0,0,0,,,,1,2,3,-1\n"),
            "run.csv:5: column fault: expected a fault code (an integer in [0, 65535]), got '-1'");
  EXPECT_EQ(expect_error(head + "0,0,0,0,0,0,0,,,,1,2,3,65536\n"),
            "run.csv:5: column fault: expected a fault code (an integer in [0, 65535]), got "
            "'65536'");
  EXPECT_EQ(expect_error(head + "0,0,0,0,0,0,0,,,,1,,3,0\n"),
            "run.csv:5: column est_y: expected a finite number, got ''");
  EXPECT_EQ(expect_error(head + "0,0,0,0,0,0,0,,,\n"), "run.csv:5: expected 14 columns, got 10");
  // Only part of the optional group is not a known layout.
  EXPECT_EQ(expect_error("# swivel-run 1\n# drivetrain: differential\n"
                         "t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,"
                         "truth_yaw,est_x\n"),
            "run.csv:3: expected header row "
            "'t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw' "
            "(optionally followed by ',est_x,est_y,est_yaw,fault'), got "
            "'t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw,est_x'");
}

TEST(RunLog, EmptyGyroAndCommandCellsMeanNoSample) {
  const std::string text = std::string(kDifferentialHead) +
                           "0,,,,0,0,,1,2,3\n"             // neither gyro nor command
                           "0.05,0.1,0,0.2,0.5,0.6,,,,\n"  // a command, no gyro
                           "0.1,,,,1,1.2,0.25,,,\n";       // a gyro sample, no command
  std::istringstream in(text);
  const RunLog log = parse_run_log(in, "lab.csv");
  ASSERT_EQ(log.samples.size(), 3U);
  EXPECT_FALSE(log.samples[0].has_gyro);
  EXPECT_FALSE(log.samples[0].has_cmd);
  EXPECT_EQ(log.samples[0].gyro_wz_radps, 0.0);
  EXPECT_EQ(log.samples[0].cmd.vx_mps, 0.0);
  EXPECT_TRUE(log.samples[0].has_truth);
  EXPECT_FALSE(log.samples[1].has_gyro);
  EXPECT_TRUE(log.samples[1].has_cmd);
  EXPECT_EQ(log.samples[1].cmd.wz_radps, 0.2);
  EXPECT_TRUE(log.samples[2].has_gyro);
  EXPECT_EQ(log.samples[2].gyro_wz_radps, 0.25);
  EXPECT_FALSE(log.samples[2].has_cmd);

  // Written back, the absent samples are empty cells again, whatever the fields hold.
  std::ostringstream out;
  RunLogWriter writer(out, log.header);
  for (RunLogSample s : log.samples) {
    if (!s.has_gyro) s.gyro_wz_radps = 9.0;
    if (!s.has_cmd) s.cmd = Twist2{9.0, 9.0, 9.0};
    writer.write(s);
  }
  EXPECT_EQ(out.str(), text);
}

TEST(RunLog, PartlyEmptyCommandCellsNameLineAndColumn) {
  EXPECT_EQ(
      expect_error(std::string(kDifferentialHead) + "0,0,0,0,0,0,0,,,\n0.1,0.2,,0,0,0,0,,,\n"),
      "run.csv:6: column cmd_vy: empty, but cmd_vx, cmd_vy and cmd_wz must be all present "
      "or all empty");
  EXPECT_EQ(expect_error(std::string(kDifferentialHead) + "0,,0,,0,0,0,,,\n"),
            "run.csv:5: column cmd_vx and cmd_wz: empty, but cmd_vx, cmd_vy and cmd_wz must be "
            "all present or all empty");
}

TEST(RunLog, UnwrapNearMovesByWholeTurns) {
  const double turn = 2.0 * std::numbers::pi;
  EXPECT_DOUBLE_EQ(unwrap_near(-3.1, 3.1), -3.1 + turn);
  EXPECT_DOUBLE_EQ(unwrap_near(3.1, -3.1), 3.1 - turn);
  EXPECT_DOUBLE_EQ(unwrap_near(0.2, 0.1), 0.2);
  EXPECT_DOUBLE_EQ(unwrap_near(-3.0, 3.0 + 2.0 * turn), -3.0 + 3.0 * turn);
}

TEST(RunLog, WrappedSteeringReadsLikeItsUnwrappedTwin) {
  // Module 1 turns steadily through +pi twice; module 2 turns the other way through -pi.
  constexpr int kRows = 200;
  RunLog wrapped;
  wrapped.header = swpc_header(2);
  RunLog twin = wrapped;
  for (int k = 0; k < kRows; ++k) {
    RunLogSample s;
    s.t_s = 0.01 * k;
    s.steer_rad[0] = 2.9 + 0.07 * k;
    s.steer_rad[1] = -3.0 - 0.05 * k;
    twin.samples.push_back(s);
    for (std::size_t i = 0; i < 2; ++i) {
      // what an absolute encoder reports: (-pi, pi]
      s.steer_rad[i] = std::remainder(s.steer_rad[i], 2.0 * std::numbers::pi);
      if (s.steer_rad[i] <= -std::numbers::pi) s.steer_rad[i] += 2.0 * std::numbers::pi;
    }
    wrapped.samples.push_back(s);
  }
  ASSERT_GT(twin.samples.back().steer_rad[0], 3.0 * std::numbers::pi);  // it does wrap, twice
  unwrap_steering(wrapped);
  RunLog unchanged = twin;
  unwrap_steering(unchanged);
  for (int k = 0; k < kRows; ++k) {
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_NEAR(wrapped.samples[k].steer_rad[i], twin.samples[k].steer_rad[i], 1e-12)
          << "row " << k << " module " << i + 1;
      EXPECT_EQ(unchanged.samples[k].steer_rad[i], twin.samples[k].steer_rad[i]);
    }
  }
}

TEST(RunLog, WriterRejectsImpossibleHeaders) {
  std::ostringstream out;
  EXPECT_THROW(RunLogWriter(out, RunLogHeader{"x", DrivetrainKind::kDifferential, 3, {}, false}),
               RunLogError);
  EXPECT_THROW(RunLogWriter(out, swpc_header(1)), RunLogError);
  EXPECT_THROW(RunLogWriter("/nonexistent-dir/run.csv", swpc_header(4)), RunLogError);
}

TEST(RunLog, GyroTimingDeclarationIsReadAndWrittenBack) {
  // Default: the reading at t, and nothing written.
  std::istringstream plain(std::string(kDifferentialHead) + "0,0,0,0,0,0,0,,,\n");
  EXPECT_FALSE(parse_run_log(plain, "run.csv").header.gyro_mean_over_row);
  const std::string declared =
      "# swivel-run 1\n# robot: docent\n# drivetrain: differential\n"
      "#gyro_wz:  mean over the row\n"
      "t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw\n"
      "0,0,0,0,0,0,0.5,,,\n";
  std::istringstream in(declared);
  const RunLog log = parse_run_log(in, "run.csv");
  EXPECT_TRUE(log.header.gyro_mean_over_row);
  EXPECT_TRUE(log.header.comments.empty()) << "a declaration, not an annotation";
  std::ostringstream out;
  {
    RunLogWriter writer(out, log.header);
    writer.write(log.samples[0]);
  }
  EXPECT_NE(out.str().find("\n# gyro_wz: mean over the row\n"), std::string::npos) << out.str();
  std::istringstream again(out.str());
  EXPECT_TRUE(parse_run_log(again, "copy.csv").header.gyro_mean_over_row);
  std::istringstream stated(
      "# swivel-run 1\n# drivetrain: differential\n# gyro_wz: reading at t\n"
      "t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw\n");
  EXPECT_FALSE(parse_run_log(stated, "run.csv").header.gyro_mean_over_row);
  EXPECT_EQ(expect_error("# swivel-run 1\n# drivetrain: differential\n# gyro_wz: filtered\n"),
            "run.csv:3: expected '# gyro_wz: mean over the row' or '# gyro_wz: reading at t', "
            "got '# gyro_wz: filtered'");
}

}  // namespace
}  // namespace swivel
