// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
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

// Consistency checks on runs from Swivel's own simulator (the same world the replay uses):
// every hidden effect is named under its question and recovered. The evidence that the
// workflow is right on data it did not make is the independent battery
// (tests/independent_robot, battery_test.cpp).

struct HiddenParam {
  std::string effect;
  std::string param;
  double value;
  double tolerance;  ///< |fitted - value| allowed
};

struct HiddenCase {
  std::string robot;
  std::vector<HiddenParam> hidden;
  Question question;
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
  return analyse_gap(nominal,
                     to_run_data(testing::simulate_run(nominal, truth, c.duration_s, seed)));
}

const QuestionResult& answer(const GapResult& r, Question q) {
  return q == Question::kSensorToPose ? r.sensor : r.command;
}

class HiddenEffectTest : public ::testing::TestWithParam<HiddenCase> {};

// The hidden effect is named under its question (and nothing else anywhere), its parameter
// recovered within the stated tolerance; the other question sees no gap.
TEST_P(HiddenEffectTest, NamesTheHiddenEffectUnderItsQuestion) {
  const HiddenCase& c = GetParam();
  const GapResult r = analyse_hidden(c);
  const QuestionResult& q = answer(r, c.question);
  const QuestionResult& other =
      answer(r, c.question == Question::kSensorToPose ? Question::kCommandToMotion
                                                      : Question::kSensorToPose);
  ASSERT_EQ(q.verdict, Verdict::kNamed) << q.summary;
  EXPECT_EQ(other.verdict, Verdict::kNoSignificantGap) << other.summary;
  ASSERT_EQ(q.named.size(), 1U) << q.summary;
  const FittedEffect& e = q.named[0];
  for (const auto& h : c.hidden) {
    ASSERT_EQ(e.name, h.effect) << q.summary;
    const auto it = std::find(e.keys.begin(), e.keys.end(), h.param);
    ASSERT_NE(it, e.keys.end()) << h.param;
    const double value = e.values[static_cast<std::size_t>(it - e.keys.begin())];
    EXPECT_NEAR(value, h.value, h.tolerance) << h.effect << "." << h.param;
    EXPECT_EQ(r.augmented.effects.at(h.effect).at(h.param), value);
  }
}

// Tolerances: a few standard deviations of the fit on these 40-60 s runs.
INSTANTIATE_TEST_SUITE_P(
    Docent, HiddenEffectTest,
    ::testing::Values(
        HiddenCase{
            "docent", {{"gyro_bias", "bias_rad_s", 0.005, 0.0003}}, Question::kSensorToPose, 40.0},
        HiddenCase{
            "docent", {{"track_width", "scale", 1.05, 0.002}}, Question::kSensorToPose, 40.0},
        HiddenCase{
            "docent", {{"track_scrub", "spin_scale", 1.04, 0.004}}, Question::kSensorToPose, 40.0},
        HiddenCase{"docent",
                   {{"actuator_lag", "time_constant_s", 0.08, 0.003}},
                   Question::kCommandToMotion,
                   40.0}),
    case_name);

INSTANTIATE_TEST_SUITE_P(
    Swpc, HiddenEffectTest,
    ::testing::Values(HiddenCase{"swpc4",
                                 {{"caster_offset", "module_1_scale", 1.5, 0.1}},
                                 Question::kSensorToPose,
                                 60.0},
                      HiddenCase{"swpc4",
                                 {{"actuator_lag", "time_constant_s", 0.06, 0.004}},
                                 Question::kCommandToMotion,
                                 60.0}),
    case_name);

TEST(NoHiddenEffectTest, NamesNothingOnEitherRobot) {
  for (const char* robot : {"docent", "swpc4"}) {
    const GapResult r = analyse_hidden({robot, {}, Question::kSensorToPose, 60.0});
    EXPECT_EQ(r.sensor.verdict, Verdict::kNoSignificantGap) << robot << ": " << r.sensor.summary;
    EXPECT_EQ(r.command.verdict, Verdict::kNoSignificantGap) << robot << ": " << r.command.summary;
    EXPECT_TRUE(r.named().empty()) << robot;
    EXPECT_TRUE(r.augmented.effects.empty()) << robot;
  }
}

// Motion capture four times noisier than the model states: the fit takes it as noise, and
// says so with the channel, the size and the figure it was judged against. The same run with
// the stated noise says nothing.
TEST(StatedNoiseTest, NoisierMotionCaptureThanTheModelStatesIsReported) {
  const RobotModel nominal = testing::robot("docent");
  const GapResult clean =
      analyse_gap(nominal, to_run_data(testing::simulate_run(nominal, nominal, 60.0, 5)));
  EXPECT_TRUE(clean.sensor.noise_findings.empty()) << clean.sensor.summary;
  RobotModel truth = nominal;
  truth.sensors.motion_capture.yaw_noise_rad *= 4.0;
  const GapResult noisy =
      analyse_gap(nominal, to_run_data(testing::simulate_run(nominal, truth, 60.0, 5)));
  ASSERT_FALSE(noisy.sensor.noise_findings.empty()) << noisy.sensor.summary;
  const NoiseFinding& f = noisy.sensor.noise_findings.front();
  EXPECT_EQ(f.channel.kind, ChannelKind::kHeading) << f.channel.name;
  EXPECT_GT(f.ratio, 2.0);
  EXPECT_LT(f.ratio, 6.0);
  EXPECT_NE(f.source.find("motion_capture.yaw_noise_rad"), std::string::npos) << f.source;
  EXPECT_NE(noisy.sensor.summary.find("Noise larger than the model states"), std::string::npos);
  for (const NoiseFinding& n : noisy.sensor.noise_findings)
    EXPECT_NE(n.channel.kind, ChannelKind::kPosition) << n.channel.name << " " << n.ratio;
}

// A wheel whose effective radius varies with its angle (an eccentric wheel) is outside the
// library: the workflow must not pass it off as a wheel radius error.
TEST(OutsideLibraryTest, EccentricWheelIsReportedAsUnexplained) {
  const RobotModel nominal = testing::robot("docent");
  RunLog log = testing::simulate_run(nominal, nominal, 60.0, 11);
  testing::add_eccentric_wheel(log, 0.03);
  const GapResult r = analyse_gap(nominal, to_run_data(log));
  EXPECT_EQ(r.sensor.verdict, Verdict::kUnexplained) << r.sensor.summary;
  EXPECT_TRUE(r.named().empty()) << r.summary;
  EXPECT_NE(r.sensor.summary.find("Unexplained residual"), std::string::npos);
}

class MalformedLogTest : public ::testing::Test {
 protected:
  std::string write_log(const std::string& name) {
    const RobotModel nominal = testing::robot("docent");
    const RunLog log = testing::simulate_run(nominal, nominal, 1.0, 3);
    dir_ =
        std::filesystem::temp_directory_path() / ("swivel_gap_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    std::string path = (dir_ / name).string();
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
  static void write_lines(const std::string& path, const std::vector<std::string>& ls,
                          bool final_newline) {
    std::ofstream out(path, std::ios::trunc);
    for (std::size_t i = 0; i < ls.size(); ++i)
      out << ls[i] << (i + 1 < ls.size() || final_newline ? "\n" : "");
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

TEST_F(MalformedLogTest, RunTooShortForItsWindowsIsRefusedWithTheReason) {
  const std::string path = write_log("short.csv");  // one second of data
  try {
    (void)analyse_gap(testing::robot("docent"), load_run(path));
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("needs at least 10"), std::string::npos) << e.what();
  }
}

// The report files exist and the JSON names the effect with its uncertainty.
TEST(ReportTest, WritesJsonMarkdownPlotsAndTheAugmentedModel) {
  const GapResult r = analyse_hidden(
      {"docent", {{"gyro_bias", "bias_rad_s", 0.005, 0.0}}, Question::kSensorToPose, 30.0});
  const auto dir =
      std::filesystem::temp_directory_path() / ("swivel_gap_report_" + std::to_string(::getpid()));
  write_report(r, dir.string());
  std::ifstream json(dir / "report.json");
  std::stringstream text;
  text << json.rdbuf();
  const nlohmann::json j = nlohmann::json::parse(text.str());
  EXPECT_EQ(j["verdicts"]["sensor_to_pose"], "named");
  EXPECT_EQ(j["verdicts"]["command_to_motion"], "no significant gap");
  ASSERT_EQ(j["named_effects"].size(), 1U);
  EXPECT_EQ(j["named_effects"][0]["name"], "gyro_bias");
  EXPECT_EQ(j["named_effects"][0]["question"], "sensor_to_pose");
  EXPECT_GT(j["named_effects"][0]["parameters"]["bias_rad_s"]["sigma"].get<double>(), 0.0);
  EXPECT_EQ(j["questions"].size(), 2U);
  for (const nlohmann::json& q : j["questions"]) {
    EXPECT_TRUE(q["attributed_gap"].is_array()) << "named by attribution: the test that found it";
    for (const nlohmann::json& m : q["misfit_tests"]) {
      EXPECT_TRUE(m["remnant"].is_boolean());
      ASSERT_TRUE(m["jumps"].is_array());  // where a jumps test's jumps are
      if (m["test"] != "jumps") {
        EXPECT_TRUE(m["jumps"].empty());
      }
    }
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "report.md"));
  const RobotModel augmented = load_robot_model((dir / "model_augmented.yaml").string());
  // Folded into the robot's own gyro bias, the one the daemon's localization corrects with.
  EXPECT_TRUE(augmented.effects.empty());
  EXPECT_NEAR(augmented.sensors.gyro.bias_rad_s, 0.005, 0.0003);
  ASSERT_EQ(j["model_augmented"]["folded"].size(), 1U);
  EXPECT_EQ(j["model_augmented"]["folded"][0].get<std::string>().rfind("gyro_bias.bias_rad_s", 0),
            0U);
  EXPECT_TRUE(j["questions"][1]["undecided"].is_null()) << "nothing the run leans towards";
  // A lean (as give_verdict() sets it) with its figures.
  GapResult leaning = r;
  CandidateScore lag;
  lag.effects = {"steering_lag"};
  lag.param_names = {"steering_lag.time_constant_s"};
  lag.values = {0.057};
  lag.sigmas = {0.012};
  lag.z = {3.8};
  lag.explained = 0.71;
  leaning.command.undecided = Undecided{lag, 6.1, 16.9, 8.6, {27.2, 31.3}, 0.4};
  write_report(leaning, dir.string());
  std::ifstream again(dir / "report.json");
  const nlohmann::json u = nlohmann::json::parse(again)["questions"][1]["undecided"];
  EXPECT_EQ(u["effects"][0], "steering_lag");
  EXPECT_DOUBLE_EQ(u["parameters"]["steering_lag.time_constant_s"]["value"].get<double>(), 0.057);
  EXPECT_DOUBLE_EQ(u["explained"].get<double>(), 0.71);
  EXPECT_DOUBLE_EQ(u["z"].get<double>(), 3.8);
  EXPECT_DOUBLE_EQ(u["z_on_many_windows"].get<double>(), 8.6);
  EXPECT_DOUBLE_EQ(u["windows"].get<double>(), 6.1);
  EXPECT_DOUBLE_EQ(u["widening"].get<double>(), 16.9);
  EXPECT_EQ(u["where_s"].get<std::vector<double>>(), (std::vector<double>{27.2, 31.3}));
  EXPECT_DOUBLE_EQ(u["where_share"].get<double>(), 0.4);
  // A fixed command, only asking whether gnuplot is installed.
  if (std::system("gnuplot --version > /dev/null 2>&1") == 0) {  // NOLINT(cert-env33-c)
    EXPECT_TRUE(std::filesystem::exists(dir / "trajectory.png"));
    EXPECT_TRUE(std::filesystem::exists(dir / "residuals.png"));
    EXPECT_GT(std::filesystem::file_size(dir / "residuals.png"), 10000U);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace swivel::model_gap
