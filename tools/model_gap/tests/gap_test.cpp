#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "gap_fixtures.hpp"
#include "swivel/model_gap/run_log_adapter.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_log.hpp"

namespace swivel::model_gap {
namespace {

struct HiddenParam {
  std::string effect;
  std::string param;
  double value;
  double tolerance;  ///< |fitted - value| allowed
};

struct HiddenCase {
  std::string robot;
  std::vector<HiddenParam> hidden;
  double duration_s;
};

std::string case_name(const ::testing::TestParamInfo<HiddenCase>& info) {
  std::string name = info.param.robot;
  for (const auto& h : info.param.hidden) name += "_" + h.effect;
  return name;
}

GapResult analyse_hidden(const HiddenCase& c, std::uint64_t seed = 7) {
  const RobotModel nominal = testing::robot(c.robot);
  RobotModel truth = nominal;
  for (const auto& h : c.hidden) truth.effects[h.effect][h.param] = h.value;
  return analyse_gap(nominal, to_run_data(testing::simulate_run(nominal, truth, c.duration_s, seed)));
}

const ChannelReport& worst_channel(const GapResult& r) {
  std::size_t worst = 0;
  for (std::size_t c = 0; c < r.channels.size(); ++c) {
    if (r.channels[c].whitened_rms_validation_before >
        r.channels[worst].whitened_rms_validation_before) {
      worst = c;
    }
  }
  return r.channels[worst];
}

class HiddenEffectTest : public ::testing::TestWithParam<HiddenCase> {};

// Every hidden effect is named (and nothing else), its parameter is recovered within the
// stated tolerance, and the worst channel's gap shrinks at least tenfold.
TEST_P(HiddenEffectTest, NamesTheHiddenEffectAndShrinksTheGap) {
  const HiddenCase& c = GetParam();
  const GapResult r = analyse_hidden(c);
  ASSERT_EQ(r.verdict, Verdict::kNamed) << r.summary;
  std::vector<std::string> expected;
  for (const auto& h : c.hidden) {
    if (std::find(expected.begin(), expected.end(), h.effect) == expected.end()) expected.push_back(h.effect);
  }
  ASSERT_EQ(r.named.size(), expected.size()) << r.summary;
  for (const auto& h : c.hidden) {
    const auto it = std::find_if(r.named.begin(), r.named.end(),
                                 [&](const FittedEffect& e) { return e.name == h.effect; });
    ASSERT_NE(it, r.named.end()) << h.effect << " not named: " << r.summary;
    ASSERT_EQ(it->values.count(h.param), 1U);
    EXPECT_NEAR(it->values.at(h.param), h.value, h.tolerance) << h.effect << "." << h.param;
    EXPECT_EQ(r.augmented.effects.at(h.effect).at(h.param), it->values.at(h.param));
  }
  const ChannelReport& worst = worst_channel(r);
  EXPECT_GT(worst.rms_before, 10.0 * worst.rms_after) << worst.info.name;
}

// Tolerances: a few standard deviations of the fit on these 30-40 s runs, widened where the
// swpc replay's coarser integration step biases the estimate (actuator lag).
INSTANTIATE_TEST_SUITE_P(
    Docent, HiddenEffectTest,
    ::testing::Values(
        HiddenCase{"docent", {{"gyro_bias", "bias_rad_s", 0.005, 0.0003}}, 40.0},
        HiddenCase{"docent", {{"gyro_scale", "scale", 1.02, 0.003}}, 40.0},
        HiddenCase{"docent", {{"wheel_radius", "left_scale", 1.01, 0.001}, {"wheel_radius", "right_scale", 1.0, 0.001}}, 40.0},
        HiddenCase{"docent", {{"track_width", "scale", 1.05, 0.003}}, 40.0},
        HiddenCase{"docent", {{"slip", "gain_per_radps2", 0.01, 0.0015}}, 40.0},
        HiddenCase{"docent", {{"actuator_lag", "time_constant_s", 0.08, 0.003}}, 40.0},
        HiddenCase{"docent", {{"sensor_latency", "delay_s", 0.03, 0.002}}, 40.0},
        HiddenCase{"docent", {{"gyro_bias", "bias_rad_s", 0.004, 0.0003}, {"wheel_radius", "right_scale", 0.99, 0.001}}, 40.0}),
    case_name);

INSTANTIATE_TEST_SUITE_P(
    Swpc, HiddenEffectTest,
    ::testing::Values(
        HiddenCase{"swpc4", {{"gyro_bias", "bias_rad_s", 0.005, 0.0003}}, 30.0},
        HiddenCase{"swpc4", {{"gyro_scale", "scale", 1.02, 0.003}}, 30.0},
        HiddenCase{"swpc4", {{"caster_offset", "module_1_scale", 1.5, 0.08}}, 30.0},
        HiddenCase{"swpc4", {{"steering_offset", "module_3_rad", 0.05, 0.008}, {"steering_offset", "module_1_rad", 0.0, 0.008}}, 30.0},
        HiddenCase{"swpc4", {{"slip", "gain_per_radps2", 0.01, 0.003}}, 30.0},
        HiddenCase{"swpc4", {{"actuator_lag", "time_constant_s", 0.08, 0.006}}, 30.0},
        HiddenCase{"swpc4", {{"sensor_latency", "delay_s", 0.03, 0.003}}, 30.0}),
    case_name);

// On a four-caster robot a diagonal pattern of radius errors (modules 1 and 3 against 2 and
// 4) moves the robot nowhere: only the radii up to that pattern are observable.
TEST(SwpcWheelRadiusTest, RecoversTheRadiiUpToTheUnobservableDiagonalPattern) {
  const GapResult r = analyse_hidden({"swpc4", {{"wheel_radius", "module_2_scale", 0.98, 0.0}}, 30.0});
  ASSERT_EQ(r.verdict, Verdict::kNamed) << r.summary;
  ASSERT_EQ(r.named.size(), 1U);
  ASSERT_EQ(r.named[0].name, "wheel_radius");
  const double truth[4] = {1.0, 0.98, 1.0, 1.0};
  const double pattern[4] = {0.5, -0.5, 0.5, -0.5};
  double error[4];
  double along = 0.0;
  for (int i = 0; i < 4; ++i) {
    error[i] = r.named[0].values.at("module_" + std::to_string(i + 1) + "_scale") - truth[i];
    along += error[i] * pattern[i];
  }
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(error[i] - along * pattern[i], 0.0, 0.002) << "module " << i + 1;
  const ChannelReport& worst = worst_channel(r);
  EXPECT_GT(worst.rms_before, 10.0 * worst.rms_after) << worst.info.name;
}

TEST(NoHiddenEffectTest, NamesNothingOnEitherRobot) {
  for (const char* robot : {"docent", "swpc4"}) {
    const GapResult r = analyse_hidden({robot, {}, 30.0});
    EXPECT_EQ(r.verdict, Verdict::kNoSignificantGap) << robot << ": " << r.summary;
    EXPECT_TRUE(r.named.empty()) << robot;
    EXPECT_TRUE(r.augmented.effects.empty()) << robot;
  }
}

// A wheel whose effective radius varies with its angle (an eccentric wheel) is outside the
// library: the workflow must not pass it off as a wheel radius error.
TEST(OutsideLibraryTest, EccentricWheelIsReportedAsUnexplained) {
  const RobotModel nominal = testing::robot("docent");
  RunLog log = testing::simulate_run(nominal, nominal, 40.0, 11);
  testing::add_eccentric_wheel(log, 0.03);
  const GapResult r = analyse_gap(nominal, to_run_data(log));
  EXPECT_EQ(r.verdict, Verdict::kUnexplained) << r.summary;
  EXPECT_TRUE(r.named.empty()) << r.summary;
  EXPECT_FALSE(r.unexplained_channel.empty());
  EXPECT_NE(r.summary.find("Unexplained residual"), std::string::npos);
}

class MalformedLogTest : public ::testing::Test {
 protected:
  std::string write_log(const std::string& name) {
    const RobotModel nominal = testing::robot("docent");
    const RunLog log = testing::simulate_run(nominal, nominal, 1.0, 3);
    dir_ = std::filesystem::temp_directory_path() / ("swivel_gap_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    const std::string path = (dir_ / name).string();
    RunLogWriter writer(path, log.header);
    for (const auto& s : log.samples) writer.write(s);
    writer.flush();
    return path;
  }
  static std::vector<std::string> lines(const std::string& path) {
    std::ifstream in(path);
    std::vector<std::string> out;
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  }
  static void write_lines(const std::string& path, const std::vector<std::string>& ls, bool final_newline) {
    std::ofstream out(path, std::ios::trunc);
    for (std::size_t i = 0; i < ls.size(); ++i) out << ls[i] << (i + 1 < ls.size() || final_newline ? "\n" : "");
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

std::string error_of(const std::string& path) {
  try {
    (void)load_run(path);
  } catch (const RunLogError& e) {
    return e.what();
  }
  return "";
}

TEST_F(MalformedLogTest, BadCellNamesTheLine) {
  const std::string path = write_log("bad_cell.csv");
  auto ls = lines(path);
  const std::size_t row = 30;  // 0-based index into the file
  ls[row].replace(ls[row].find(','), 1, ",abc,");
  write_lines(path, ls, true);
  const std::string msg = error_of(path);
  EXPECT_NE(msg.find("bad_cell.csv:" + std::to_string(row + 1) + ":"), std::string::npos) << msg;
}

TEST_F(MalformedLogTest, TruncatedLastRowNamesTheLine) {
  const std::string path = write_log("truncated.csv");
  auto ls = lines(path);
  ls.back() = ls.back().substr(0, ls.back().size() / 2);
  write_lines(path, ls, false);
  const std::string msg = error_of(path);
  EXPECT_NE(msg.find("truncated.csv:" + std::to_string(ls.size()) + ":"), std::string::npos) << msg;
}

TEST_F(MalformedLogTest, RunFromAnotherRobotIsRefused) {
  const std::string path = write_log("docent.csv");
  const RobotModel swpc = testing::robot("swpc4");
  EXPECT_THROW(analyse_gap(swpc, load_run(path)), std::invalid_argument);
}

// The report files exist and the JSON names the effect with its uncertainty.
TEST(ReportTest, WritesJsonMarkdownPlotsAndTheAugmentedModel) {
  const GapResult r = analyse_hidden({"docent", {{"gyro_bias", "bias_rad_s", 0.005, 0.0}}, 30.0});
  const auto dir = std::filesystem::temp_directory_path() / ("swivel_gap_report_" + std::to_string(::getpid()));
  write_report(r, dir.string());
  std::ifstream json(dir / "report.json");
  std::stringstream text;
  text << json.rdbuf();
  EXPECT_NE(text.str().find("\"name\": \"gyro_bias\""), std::string::npos);
  EXPECT_NE(text.str().find("\"sigma\""), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "report.md"));
  const RobotModel augmented = load_robot_model((dir / "model_augmented.yaml").string());
  EXPECT_NEAR(augmented.effects.at("gyro_bias").at("bias_rad_s"), 0.005, 0.0003);
  if (std::system("gnuplot --version > /dev/null 2>&1") == 0) {
    EXPECT_TRUE(std::filesystem::exists(dir / "trajectory.png"));
    EXPECT_TRUE(std::filesystem::exists(dir / "residuals.png"));
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace swivel::model_gap
