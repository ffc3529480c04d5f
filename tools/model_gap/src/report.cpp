// SPDX-License-Identifier: Apache-2.0
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "swivel/model_gap/fold_effects.hpp"
#include "swivel/model_gap/workflow.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::model_gap {
namespace {

using nlohmann::json;

// JSON has no NaN or infinity; absent values become null.
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json effects_json(const std::vector<FittedEffect>& effects, Question q) {
  json out = json::array();
  for (const auto& e : effects) {
    json params = json::object();
    for (std::size_t i = 0; i < e.keys.size(); ++i) {
      params[e.keys[i]] = {{"value", number(e.values[i])},
                           {"sigma", number(e.sigmas[i])},
                           {"sigma_of_observable_part", number(e.partial_sigmas[i])}};
    }
    out.push_back({{"name", e.name},
                   {"observable_combinations", e.observable_combinations},
                   {"question", question_name(q)},
                   {"section", e.limits ? "limits" : "effects"},
                   {"z", number(e.z)},
                   {"parameters", params}});
  }
  return out;
}

// The candidate a verdict with nothing named leans towards (question.hpp, Undecided), or null.
json undecided_json(const std::optional<Undecided>& u) {
  if (!u) return nullptr;
  json params = json::object();
  const CandidateScore& c = u->candidate;
  for (std::size_t i = 0; i < c.param_names.size(); ++i)
    params[c.param_names[i]] = {{"value", number(c.values[i])}, {"sigma", number(c.sigmas[i])}};
  return {{"effects", c.effects},
          {"parameters", params},
          {"explained", number(c.explained)},
          {"z", number(c.z.empty() ? 0.0 : c.z[0])},
          {"z_on_many_windows", number(u->z_many)},
          {"windows", number(u->windows)},
          {"widening", number(u->widening)},
          {"where_s", u->where_s},
          {"where_share", number(u->where_share)}};
}

json question_json(const QuestionResult& q) {
  json j;
  j["question"] = question_name(q.question);
  j["verdict"] = verdict_name(q.verdict);
  j["summary"] = q.summary;
  j["named_effects"] = effects_json(q.named, q.question);
  j["calibrated_effects"] = effects_json(q.calibrated, q.question);
  json cands = json::array();
  for (const auto& c : q.candidates) {
    json params = json::object();
    for (std::size_t i = 0; i < c.param_names.size(); ++i) {
      params[c.param_names[i]] = {{"value", number(c.values[i])}, {"sigma", number(c.sigmas[i])}};
    }
    json z = json::array();
    for (double v : c.z) z.push_back(number(v));
    cands.push_back({{"effects", c.effects},
                     {"ok", c.ok},
                     {"parameters", params},
                     {"z", z},
                     {"bic", number(c.bic)},
                     {"delta_bic", number(c.delta_bic)},
                     {"explained", number(c.explained)},
                     {"iterations", c.iterations}});
  }
  j["candidates"] = cands;
  const auto misfits_json = [](const std::vector<MisfitTest>& tests) {
    json out = json::array();
    for (const auto& m : tests) {
      json windows = json::array();  // jumps: each jump's first window (count 2: a pair)
      for (const MisfitTest::Span& span : m.jumps)
        windows.push_back({{"window", span.first}, {"count", span.count}});
      out.push_back({{"test", m.test},
                     {"channel", m.channel},
                     {"label", m.label},
                     {"z", number(m.z)},
                     {"share", number(m.share)},
                     {"remnant", m.remnant},
                     {"jumps", windows}});
    }
    return out;
  };
  j["misfit_tests"] = misfits_json(q.misfits);
  // Named by attribution: the test that found the gap the named effects take away.
  j["attributed_gap"] = misfits_json(q.attributed_gap);
  json rivals = json::array();
  for (const CandidateScore& r : q.rivals) {
    json z = json::array();
    for (double v : r.z) z.push_back(number(v));
    rivals.push_back({{"effects", r.effects}, {"bic", number(r.bic)}, {"z", z}});
  }
  j["rivals"] = rivals;
  j["undecided"] = undecided_json(q.undecided);
  json chans = json::array();
  for (const auto& c : q.channels) {
    chans.push_back(
        {{"name", c.info.name},
         {"unit", c.info.unit},
         {"noise_sigma", number(c.noise_sigma)},
         {"rest_sigma", number(c.rest_sigma)},
         {"stated_sigma", number(c.stated_sigma)},
         {"rms", {{"before", number(c.rms_before)}, {"after", number(c.rms_after)}}},
         {"whitened_rms",
          {{"before", number(c.whitened_rms_before)}, {"after", number(c.whitened_rms_after)}}}});
  }
  j["channels"] = chans;
  json noise = json::array();
  for (const auto& f : q.noise_findings) {
    noise.push_back({{"channel", f.channel.name},
                     {"unit", f.channel.unit},
                     {"measured_sigma", number(f.measured_sigma)},
                     {"stated_sigma", number(f.stated_sigma)},
                     {"ratio", number(f.ratio)},
                     {"stated_by", f.source}});
  }
  j["noise_findings"] = noise;
  j["wall_time_s"] = q.wall_time_s;
  return j;
}

json report_json(const GapResult& r) {
  json j;
  j["run"] = r.run_source;
  j["robot"] = r.nominal.name;
  j["model"] = r.nominal.source_file;
  j["verdicts"] = {
      {"sensor_to_pose", verdict_name(r.sensor.verdict)},
      {"command_to_motion", r.command_assessed ? verdict_name(r.command.verdict) : "not assessed"}};
  j["summary"] = r.summary;
  json named = effects_json(r.sensor.named, Question::kSensorToPose);
  for (const auto& e : effects_json(r.command.named, Question::kCommandToMotion))
    named.push_back(e);
  j["named_effects"] = named;
  j["calibrated_effects"] = effects_json(r.sensor.calibrated, Question::kSensorToPose);
  {
    const FoldResult fold = fold_effects(r.augmented);
    j["model_augmented"] = {{"folded", fold.folded}, {"kept_in_effects", fold.kept}};
  }
  j["questions"] = json::array({question_json(r.sensor)});
  if (r.command_assessed) j["questions"].push_back(question_json(r.command));
  j["command_delay_s"] = r.command_delay_s;
  j["steering_yield_rad"] = r.steering_yield_rad;
  {
    json truth = json::object();
    for (std::size_t i = 0; i < std::min(r.truth_names.size(), r.sensor.nuisance.size()); ++i) {
      const double sigma = i < r.sensor.nuisance_sigmas.size()
                               ? r.sensor.nuisance_sigmas[i]
                               : std::numeric_limits<double>::infinity();
      truth[r.truth_names[i]] = {{"value", r.sensor.nuisance[i]},
                                 {"sigma", std::isfinite(sigma) ? json(sigma) : json(nullptr)}};
    }
    j["motion_capture_nuisance"] = truth;
    j["notes"] = r.notes;
  }
  j["window_s"] = r.options.window_s;
  j["wall_time_s"] = r.wall_time_s;
  j["thresholds"] = {{"min_z_name", r.options.question.min_z_name},
                     {"min_z_misfit", r.options.question.min_z_misfit},
                     {"max_effects", r.options.question.max_effects}};
  json poses = json::array();
  for (const auto& p : r.pose_gaps) {
    poses.push_back(
        {{"question", question_name(p.question)},
         {"rms_position_m",
          {{"before", number(p.rms_position_m_before)}, {"after", number(p.rms_position_m_after)}}},
         {"final_position_m",
          {{"before", number(p.final_position_m_before)},
           {"after", number(p.final_position_m_after)}}},
         {"rms_heading_rad",
          {{"before", number(p.rms_heading_rad_before)},
           {"after", number(p.rms_heading_rad_after)}}},
         {"final_heading_rad",
          {{"before", number(p.final_heading_rad_before)},
           {"after", number(p.final_heading_rad_after)}}}});
  }
  j["gap"]["pose"] = poses;
  json segs = json::array();
  for (const auto& s : r.segments) {
    segs.push_back({{"phase", phase_name(s.kind)}, {"start_s", s.start_s}, {"end_s", s.end_s}});
  }
  j["phases"] = segs;
  return j;
}

std::string fmt(double v, int precision = 4) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

std::string ratio(double before, double after) {
  if (!std::isfinite(before) || !std::isfinite(after) || after <= 0.0) return "-";
  return fmt(before / after, 3) + "x";
}

// paths.dat: t, motion capture x y, dead reckoning before x y, after x y, replay before x y,
// after x y.
void write_paths(const GapResult& r, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << std::setprecision(9);
  const std::size_t stride = std::max<std::size_t>(1, r.t_s.size() / 3000);
  const auto xy = [&out](const std::vector<Pose2>& p, std::size_t k) {
    if (k < p.size() && std::isfinite(p[k].x_m)) {
      out << ' ' << p[k].x_m << ' ' << p[k].y_m;
    } else {
      out << " nan nan";
    }
  };
  for (std::size_t k = 0; k < r.t_s.size(); k += stride) {
    out << r.t_s[k];
    xy(r.motion_capture, k);
    xy(r.dead_reckoning_before, k);
    xy(r.dead_reckoning_after, k);
    xy(r.replay_before, k);
    xy(r.replay_after, k);
    out << '\n';
  }
}

// windows.dat: window start, then per channel of both questions: residual before, after.
void write_windows(const GapResult& r, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << std::setprecision(9);
  const std::size_t w = r.window_start_s.size();
  for (std::size_t j = 0; j < w; ++j) {
    out << r.window_start_s[j];
    for (const QuestionResult* q : {&r.sensor, &r.command}) {
      for (std::size_t c = 0; c < q->channels.size(); ++c) {
        out << ' ' << q->residuals_before[c * w + j] << ' ' << q->residuals_after[c * w + j];
      }
    }
    out << '\n';
  }
}

std::string plot_script(const GapResult& r) {
  std::ostringstream g;
  g << "set terminal pngcairo noenhanced size 1000,800 font 'sans,10'\n"
    << "set datafile missing 'nan'\nset key outside bottom center horizontal\nset grid\n"
    << "set output 'trajectory.png'\nset title 'Path: motion capture against both replays'\n"
    << "set size ratio -1\nset xlabel 'x (m)'\nset ylabel 'y (m)'\n"
    << "plot 'paths.dat' u 2:3 w l lw 3 lc rgb 'black' t 'motion capture', \\\n"
    << "  '' u 4:5 w l lc rgb '#d62728' t 'dead reckoning, nominal', \\\n"
    << "  '' u 6:7 w l lc rgb '#2ca02c' t 'dead reckoning, augmented'";
  if (r.command_assessed) {
    g << ", \\\n  '' u 8:9 w l dt 2 lc rgb '#ff7f0e' t 'command replay, nominal', \\\n"
      << "  '' u 10:11 w l dt 2 lc rgb '#1f77b4' t 'command replay, augmented'";
  }
  g << "\nset size noratio\n";
  std::size_t n = r.sensor.channels.size() + r.command.channels.size();
  const std::size_t rows = (n + 1) / 2;
  g << "set output 'residuals.png'\nset terminal pngcairo noenhanced size 1200," << 200 * rows + 60
    << " font 'sans,9'\nset multiplot layout " << rows
    << ",2 title 'Residual per window (measured - predicted change): nominal and augmented'\n"
    << "set key inside top left\nset xlabel 't (s)'\n";
  std::size_t column = 2;
  for (const QuestionResult* q : {&r.sensor, &r.command}) {
    for (const ChannelGap& c : q->channels) {
      g << "set title '" << c.info.name << " (" << c.info.unit << ")'\nset ylabel ''\n"
        << "plot 'windows.dat' u 1:" << column
        << " w l lc rgb '#d62728' t 'nominal', '' u 1:" << column + 1
        << " w l lc rgb '#2ca02c' t 'augmented'\n";
      column += 2;
    }
  }
  g << "unset multiplot\n";
  return g.str();
}

bool run_gnuplot(const std::string& dir) {
  const std::string cmd = "cd '" + dir + "' && gnuplot plots.gp > gnuplot.log 2>&1";
  // gnuplot is a program of its own; the directory is the report's, quoted.
  return std::system(cmd.c_str()) == 0;  // NOLINT(cert-env33-c)
}

// The fitted effects' parameters as a table, with a note when some are not observable alone.
void effects_markdown(std::ostringstream& md, const std::vector<FittedEffect>& effects) {
  if (effects.empty()) return;
  md << "| effect | parameter | value | 1 sigma | significance |\n|---|---|---|---|---|\n";
  bool partial = false;
  for (const auto& e : effects) {
    for (std::size_t i = 0; i < e.keys.size(); ++i) {
      const bool alone = std::isfinite(e.sigmas[i]);
      partial = partial || !alone;
      md << "| " << e.name << " | " << (e.limits ? "limits." : "") << e.keys[i] << " | "
         << fmt(e.values[i], 6) << " | "
         << (alone ? fmt(e.sigmas[i], 2) : fmt(e.partial_sigmas[i], 2) + " *") << " | "
         << fmt(e.z, 3) << " sigma |\n";
    }
  }
  md << "\n";
  if (partial) {
    md << "\\* Not observable alone: the run fixes only some combinations of these parameters (";
    for (const auto& e : effects) {
      if (e.observable_combinations < e.keys.size()) {
        md << e.name << ": " << e.observable_combinations << " of " << e.keys.size() << "; ";
      }
    }
    md << "the rest stay at the model's values); the sigma is that of the part the run "
          "fixes.\n\n";
  }
}

void question_markdown(std::ostringstream& md, const QuestionResult& q, const QuestionOptions& o) {
  md << "## " << question_title(q.question) << ": " << verdict_name(q.verdict) << "\n\n"
     << q.summary << "\n\n";
  effects_markdown(md, q.named);
  if (!q.calibrated.empty()) {
    md << "Calibrated: a parameter of the robot's own model that the run fixes, significant at "
       << fmt(o.min_z_calibrate, 2)
       << " sigma or more though its change per window is too small to name a missing effect "
          "(it adds up over the run); folded into `model_augmented.yaml`.\n\n";
    effects_markdown(md, q.calibrated);
  }
  md << "| channel | unit | noise (1 sigma) | RMS before | RMS after | shrink | whitened RMS "
        "before -> after |\n"
     << "|---|---|---|---|---|---|---|\n";
  for (const auto& c : q.channels) {
    md << "| " << c.info.name << " | " << c.info.unit << " | " << fmt(c.noise_sigma, 3) << " | "
       << fmt(c.rms_before) << " | " << fmt(c.rms_after) << " | "
       << ratio(c.rms_before, c.rms_after) << " | " << fmt(c.whitened_rms_before, 3) << " -> "
       << fmt(c.whitened_rms_after, 3) << " |\n";
  }
  if (!q.noise_findings.empty()) {
    md << "\nNoise larger than the model states (the noise every window has, against what the "
          "model's sensor figures give: the sensors are noisier than the model says, or "
          "something the library does not hold varies from window to window; the fit took it "
          "as noise, so effects smaller than it stay hidden):\n\n| channel | measured (1 sigma) | "
          "stated | ratio | stated by |\n"
       << "|---|---|---|---|---|\n";
    for (const auto& f : q.noise_findings) {
      md << "| " << f.channel.name << " | " << fmt(f.measured_sigma, 3) << " " << f.channel.unit
         << " | " << fmt(f.stated_sigma, 3) << " | " << fmt(f.ratio, 3) << "x | " << f.source
         << " |\n";
    }
  }
  md << "\nTests for what the library does not hold, on the residual that remains (most "
        "significant first; a test at or above "
     << fmt(o.min_z_misfit, 3) << " sigma makes the residual unexplained):\n\n";
  for (std::size_t i = 0; i < q.misfits.size() && i < 5; ++i) {
    const MisfitTest& m = q.misfits[i];
    md << "- " << m.test << " on `" << m.channel << "`: " << m.label << ", " << fmt(m.z, 3)
       << " sigma\n";
  }
  md << "\nCandidates (best BIC first):\n\n| effects | parameters | significance | delta BIC | "
        "explained |\n"
     << "|---|---|---|---|---|\n";
  for (const auto& c : q.candidates) {
    md << "| " << c.label() << " | ";
    for (std::size_t i = 0; i < c.param_names.size(); ++i) {
      md << (i > 0 ? ", " : "") << c.param_names[i] << " = " << fmt(c.values[i], 4) << " +- "
         << fmt(c.sigmas[i], 2);
    }
    md << " | ";
    for (std::size_t i = 0; i < c.z.size(); ++i) md << (i > 0 ? ", " : "") << fmt(c.z[i], 3);
    md << " | " << fmt(c.delta_bic, 5) << " | " << fmt(c.explained, 3) << " |\n";
  }
  md << "\n";
}

std::string markdown(const GapResult& r, bool plots) {
  std::ostringstream md;
  md << "# Model-gap report: " << r.nominal.name << "\n\n"
     << "Run `" << r.run_source << "`, model `" << r.nominal.source_file
     << "`. Each question is decided "
     << "on its own; a gap in one never vetoes a finding in the other.\n\n"
     << "| question | verdict |\n|---|---|\n| sensor to pose | " << verdict_name(r.sensor.verdict)
     << " |\n"
     << "| command to motion | "
     << (r.command_assessed ? verdict_name(r.command.verdict) : "not assessed") << " |\n\n";
  if (!r.named().empty() || !r.sensor.calibrated.empty()) {
    // What the daemon loads (fold_effects.hpp): the header of model_augmented.yaml says it too.
    const FoldResult fold = fold_effects(r.augmented);
    md << "The augmented model is `model_augmented.yaml`: the nominal model with what was named "
          "(or calibrated) folded into the robot's own parameters, which the daemon's drivetrain "
          "and localization "
          "use (fitted limits go to its `limits:` section); only what the daemon cannot use stays "
          "in `effects:`, for the simulator.\n\n";
    for (const std::string& line : fold.folded) md << "- folded: " << line << "\n";
    for (const std::string& line : fold.kept) md << "- kept in `effects:`: " << line << "\n";
    md << "\n";
  }
  md << "## Motion capture and gyro timing\n\nFitted beside every candidate of the sensor "
        "question and never named as robot effects (fix the motion-capture set-up with them; "
        "the gyro's is where between rows the rate it samples belongs):\n\n";
  for (const std::string& line : truth_nuisance_lines(r)) md << "- " << line << "\n";
  md << "\n";
  for (const std::string& note : r.notes) md << "Note: " << note << "\n\n";
  md << "## Gap over the whole run\n\n"
     << "| replay | RMS position (m) | final position (m) | RMS heading (rad) | final heading "
        "(rad) |\n"
     << "|---|---|---|---|---|\n";
  for (const auto& p : r.pose_gaps) {
    md << "| " << question_title(p.question) << " | " << fmt(p.rms_position_m_before) << " -> "
       << fmt(p.rms_position_m_after) << " ("
       << ratio(p.rms_position_m_before, p.rms_position_m_after) << ") | "
       << fmt(p.final_position_m_before) << " -> " << fmt(p.final_position_m_after) << " | "
       << fmt(p.rms_heading_rad_before) << " -> " << fmt(p.rms_heading_rad_after) << " | "
       << fmt(p.final_heading_rad_before) << " -> " << fmt(p.final_heading_rad_after) << " |\n";
  }
  if (plots) {
    md << "\n![paths](trajectory.png)\n\n![residuals](residuals.png)\n\n";
  } else {
    md << "\n(gnuplot was not available: no plots; the data are in paths.dat and windows.dat)\n\n";
  }
  question_markdown(md, r.sensor, r.options.question);
  if (r.command_assessed) {
    question_markdown(md, r.command, r.options.question);
    md << "The commands were replayed " << fmt(1000.0 * r.command_delay_s, 3)
       << " ms late (fitted with the selection; negative: early).";
    if (r.steering_yield_rad > 0.0) {
      md << " The steering servos yielded to their tyres from "
         << fmt(1000.0 * r.steering_yield_rad, 3) << " mrad of error (fitted with it).";
    }
    md << "\n\n";
  }
  md << "Motion phases (from the commands): ";
  double durations[4] = {0, 0, 0, 0};
  for (const auto& s : r.segments) durations[static_cast<int>(s.kind)] += s.end_s - s.start_s;
  for (int p = 0; p < 4; ++p) {
    md << (p > 0 ? ", " : "") << phase_name(static_cast<PhaseKind>(p)) << " "
       << fmt(durations[p], 4) << " s";
  }
  md << ".\n\nSelection: per question, the single effect with the lowest BIC among those "
        "significant at "
     << fmt(r.options.question.min_z_name, 3)
     << " sigma or more (likelihood-ratio test, widened for the residuals' autocorrelation over "
     << fmt(r.options.window_s, 3)
     << " s windows), then a second one when it is significant in the pair and "
        "lowers the BIC further. Workflow time "
     << fmt(r.wall_time_s, 3) << " s.\n";
  return md.str();
}

}  // namespace

void write_report(const GapResult& result, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create report directory " + dir + ": " + ec.message());
  const std::filesystem::path d(dir);
  {
    std::ofstream out(d / "report.json");
    if (!out) throw std::runtime_error("cannot write " + (d / "report.json").string());
    out << report_json(result).dump(2) << '\n';
  }
  {
    // The model for the robot: what has a parameter in the robot model is folded into it, so
    // that a reload changes what the daemon computes; the comment lines say what went where.
    write_folded_model(result.augmented,
                       result.nominal.name + ", as swivel-lab gap found it in " + result.run_source,
                       (d / "model_augmented.yaml").string());
  }
  write_paths(result, (d / "paths.dat").string());
  write_windows(result, (d / "windows.dat").string());
  {
    std::ofstream gp(d / "plots.gp");
    if (!gp) throw std::runtime_error("cannot write " + (d / "plots.gp").string());
    gp << plot_script(result);
  }
  const bool plots = run_gnuplot(d.string());
  std::ofstream md(d / "report.md");
  if (!md) throw std::runtime_error("cannot write " + (d / "report.md").string());
  md << markdown(result, plots);
}

}  // namespace swivel::model_gap
