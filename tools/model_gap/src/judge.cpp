// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/judge.hpp"

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

namespace swivel::model_gap {
namespace {

std::string group_of(const std::string& source) {
  const std::filesystem::path session = std::filesystem::path(source).parent_path();
  const std::string group = session.parent_path().filename().string();
  return group.empty() ? "." : group;
}

JudgedGroup summarise(const std::string& name, const std::vector<const JudgedRun*>& runs,
                      std::size_t models) {
  JudgedGroup g;
  g.group = name;
  g.runs = runs.size();
  for (std::size_t m = 0; m < models; ++m) {
    std::vector<double> gaps;
    std::vector<double> ratios;
    for (const JudgedRun* r : runs) {
      gaps.push_back(r->rms_position_m[m]);
      ratios.push_back(r->rms_position_m[m] / r->rms_position_m[0]);
    }
    g.median_rms_position_m.push_back(median(gaps));
    g.median_ratio.push_back(median(ratios));
  }
  return g;
}

std::string fmt(double v, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

}  // namespace

JudgeResult judge_models(const std::vector<RobotModel>& models,
                         const std::vector<std::string>& names, const std::vector<RunData>& runs,
                         const GapOptions& options, const CrossRunProgress& progress) {
  JudgeResult result;
  result.models = names;
  std::size_t step = 0;
  for (const RunData& run : runs) {
    JudgedRun j;
    j.run = run.source;
    j.group = group_of(run.source);
    try {
      for (const RobotModel& m : models)
        j.rms_position_m.push_back(held_out_gap(m, run, options).rms_position_m);
      result.runs.push_back(std::move(j));
    } catch (const std::exception& e) {
      result.skipped.push_back(run.source + ": " + e.what());
    }
    if (progress) progress(++step, runs.size(), "judged " + run.source);
  }
  std::map<std::string, std::vector<const JudgedRun*>> by_group;
  std::vector<const JudgedRun*> all;
  for (const JudgedRun& j : result.runs) {
    by_group[j.group].push_back(&j);
    all.push_back(&j);
  }
  for (const auto& [name, members] : by_group)
    result.groups.push_back(summarise(name, members, models.size()));
  result.groups.push_back(summarise("all", all, models.size()));
  return result;
}

void write_judge_report(const JudgeResult& r, const std::string& dir) {
  using nlohmann::json;
  std::filesystem::create_directories(dir);
  json j;
  j["models"] = r.models;
  j["skipped"] = r.skipped;
  json groups = json::array();
  for (const JudgedGroup& g : r.groups) {
    groups.push_back({{"group", g.group},
                      {"runs", g.runs},
                      {"median_rms_position_m", g.median_rms_position_m},
                      {"median_ratio", g.median_ratio}});
  }
  j["groups"] = groups;
  json runs = json::array();
  for (const JudgedRun& run : r.runs)
    runs.push_back(
        {{"run", run.run}, {"group", run.group}, {"rms_position_m", run.rms_position_m}});
  j["runs"] = runs;
  std::ofstream js(dir + "/judge.json");
  js << j.dump(2) << "\n";
  if (!js) throw std::runtime_error("cannot write " + dir + "/judge.json");

  std::ofstream md(dir + "/judge.md");
  md << "# Models judged on runs\n\nEach run's whole-run RMS position gap (sensor to pose, the "
        "run's own motion-capture nuisances fitted for each model); medians per group of runs, "
        "and the median ratio to the first model.\n\n| group | runs |";
  for (const std::string& m : r.models) md << " " << m << " |";
  md << "\n|---|---|";
  for (std::size_t m = 0; m < r.models.size(); ++m) md << "---|";
  md << "\n";
  for (const JudgedGroup& g : r.groups) {
    md << "| " << g.group << " | " << g.runs << " |";
    for (std::size_t m = 0; m < r.models.size(); ++m) {
      md << " " << fmt(1000.0 * g.median_rms_position_m[m]) << " mm";
      if (m > 0) md << " (ratio " << fmt(g.median_ratio[m]) << ")";
      md << " |";
    }
    md << "\n";
  }
  if (!r.skipped.empty()) {
    md << "\n## Runs not used\n\n";
    for (const std::string& s : r.skipped) md << "- " << s << "\n";
  }
  if (!md) throw std::runtime_error("cannot write " + dir + "/judge.md");
}

}  // namespace swivel::model_gap
