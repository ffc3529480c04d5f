#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "swivel/model_gap/workflow.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::model_gap {
namespace {

using nlohmann::json;

// JSON has no NaN or infinity; absent values become null.
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json character_json(const Character& c) {
  return {{"label", c.label}, {"signal", c.signal}, {"r_squared", number(c.r_squared)},
          {"slope", number(c.slope)}};
}

json effects_json(const std::vector<FittedEffect>& effects) {
  json out = json::array();
  for (const auto& e : effects) {
    json params = json::object();
    for (const auto& [k, v] : e.values) {
      params[k] = {{"value", number(v)}, {"sigma", number(e.sigmas.count(k) ? e.sigmas.at(k) : NAN)}};
    }
    out.push_back({{"name", e.name}, {"parameters", params}});
  }
  return out;
}

json report_json(const GapResult& r) {
  json j;
  j["run"] = r.run_source;
  j["robot"] = r.nominal.name;
  j["model"] = r.nominal.source_file;
  j["verdict"] = verdict_name(r.verdict);
  j["summary"] = r.summary;
  j["named_effects"] = effects_json(r.named);
  if (r.verdict == Verdict::kUnexplained) {
    j["unexplained"] = {{"channel", r.unexplained_channel},
                        {"character", character_json(r.unexplained_character)}};
  }
  j["holdout_start_s"] = r.holdout_start_s;
  j["wall_time_s"] = r.wall_time_s;
  j["thresholds"] = {{"holdout_fraction", r.options.holdout_fraction},
                     {"min_gap_whitened_rms", r.options.min_gap_whitened_rms},
                     {"min_explained", r.options.min_explained},
                     {"min_significance", r.options.min_significance},
                     {"min_pair_gain", r.options.min_pair_gain},
                     {"min_delta_bic", r.options.min_delta_bic}};
  json cands = json::array();
  for (const auto& c : r.candidates) {
    json params = json::object();
    for (std::size_t i = 0; i < c.param_names.size(); ++i) {
      params[c.param_names[i]] = {{"value", number(c.values[i])}, {"sigma", number(c.sigmas[i])}};
    }
    cands.push_back({{"effects", c.effects},
                     {"ok", c.ok},
                     {"parameters", params},
                     {"bic", number(c.bic)},
                     {"delta_bic", number(c.delta_bic)},
                     {"explained_training", number(c.explained_training)},
                     {"explained_validation", number(c.explained_validation)},
                     {"iterations", c.iterations}});
  }
  j["candidates"] = cands;
  json poses = json::array();
  for (const auto& p : r.pose_gaps) {
    poses.push_back({{"question", question_name(p.question)},
                     {"rms_position_m", {{"before", number(p.rms_position_m_before)}, {"after", number(p.rms_position_m_after)}}},
                     {"final_position_m", {{"before", number(p.final_position_m_before)}, {"after", number(p.final_position_m_after)}}},
                     {"rms_heading_rad", {{"before", number(p.rms_heading_rad_before)}, {"after", number(p.rms_heading_rad_after)}}},
                     {"final_heading_rad", {{"before", number(p.final_heading_rad_before)}, {"after", number(p.final_heading_rad_after)}}}});
  }
  j["gap"]["pose"] = poses;
  json chans = json::array();
  for (const auto& c : r.channels) {
    json windows = json::array();
    for (const auto& w : c.windows) {
      windows.push_back({{"start_s", w.start_s}, {"end_s", w.end_s}, {"growth", number(w.growth)},
                         {"phase", phase_name(w.dominant_phase)}});
    }
    json phases = json::array();
    for (const auto& p : c.phases) {
      phases.push_back({{"phase", phase_name(p.kind)}, {"duration_s", p.duration_s},
                        {"rms", number(p.rms)}, {"growth_per_s", number(p.growth_per_s)}});
    }
    chans.push_back({{"name", c.info.name},
                     {"unit", c.info.unit},
                     {"question", question_name(c.info.question)},
                     {"noise_sigma", number(c.noise_sigma)},
                     {"rms", {{"before", number(c.rms_before)}, {"after", number(c.rms_after)}}},
                     {"final", {{"before", number(c.final_before)}, {"after", number(c.final_after)}}},
                     {"whitened_rms_validation",
                      {{"before", number(c.whitened_rms_validation_before)},
                       {"after", number(c.whitened_rms_validation_after)}}},
                     {"character_before", character_json(c.character_before)},
                     {"character_after", character_json(c.character_after)},
                     {"growth_windows", windows},
                     {"phases", phases}});
  }
  j["gap"]["channels"] = chans;
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

// Columns: t, then for each channel measured, before, after.
void write_plot_data(const GapResult& r, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << std::setprecision(9);
  // At most about 3000 points per curve: enough for the plots, quick for gnuplot.
  const std::size_t stride = std::max<std::size_t>(1, r.t_s.size() / 3000);
  for (std::size_t k = 0; k < r.t_s.size(); k += stride) {
    out << r.t_s[k];
    for (std::size_t c = 0; c < r.measured.channel_count(); ++c) {
      const auto& info = r.measured.info[c];
      const double m = r.measured.values[c][k];
      const double b = r.before.values[c][k];
      const double a = r.after.values[c][k];
      const double rb = residual_at(info, m, b);
      const double ra = residual_at(info, m, a);
      out << ' ' << (std::isfinite(m) ? m : NAN) << ' ' << b << ' ' << a << ' ' << rb << ' ' << ra;
    }
    out << '\n';
  }
}

// gnuplot column of field f (0 measured, 1 before, 2 after, 3 residual before, 4 after).
std::string col(std::size_t channel, int field) {
  return std::to_string(2 + 5 * channel + static_cast<std::size_t>(field));
}

std::string plot_script(const GapResult& r) {
  std::ostringstream g;
  g << "set terminal pngcairo noenhanced size 1000,800 font 'sans,10'\n"
    << "set datafile missing 'nan'\nset key outside bottom center horizontal\nset grid\n";
  const auto& m = r.measured;
  const std::size_t dx = m.find("dead_reckoning.x_m");
  const std::size_t dy = m.find("dead_reckoning.y_m");
  const std::size_t sx = m.find("simulation.x_m");
  const std::size_t sy = m.find("simulation.y_m");
  g << "set output 'trajectory.png'\nset title 'Trajectory: motion capture vs predictions'\n"
    << "set size ratio -1\nset xlabel 'x (m)'\nset ylabel 'y (m)'\n"
    << "plot 'plot_data.dat' u " << col(dx, 0) << ":" << col(dy, 0)
    << " w l lw 3 lc rgb 'black' t 'motion capture', \\\n"
    << "  '' u " << col(dx, 1) << ":" << col(dy, 1) << " w l lc rgb '#d62728' t 'dead reckoning, nominal', \\\n"
    << "  '' u " << col(dx, 2) << ":" << col(dy, 2) << " w l lc rgb '#2ca02c' t 'dead reckoning, augmented', \\\n"
    << "  '' u " << col(sx, 1) << ":" << col(sy, 1) << " w l dt 2 lc rgb '#ff7f0e' t 'simulation, nominal', \\\n"
    << "  '' u " << col(sx, 2) << ":" << col(sy, 2) << " w l dt 2 lc rgb '#1f77b4' t 'simulation, augmented'\n"
    << "set size noratio\n";
  // One panel per channel: residual before and after.
  const std::size_t n = m.channel_count();
  const std::size_t rows = (n + 1) / 2;
  g << "set output 'residuals.png'\nset terminal pngcairo noenhanced size 1200," << 220 * rows << " font 'sans,9'\n"
    << "set multiplot layout " << rows << ",2 title 'Residual (measured - predicted) over time; held-out part from "
    << fmt(r.holdout_start_s, 3) << " s'\nset key inside top left\nset xlabel 't (s)'\n";
  for (std::size_t c = 0; c < n; ++c) {
    g << "set title '" << m.info[c].name << " (" << m.info[c].unit << ")'\nset ylabel ''\n"
      << "set arrow 1 from " << r.holdout_start_s << ", graph 0 to " << r.holdout_start_s
      << ", graph 1 nohead dt 3 lc rgb 'gray'\n"
      << "plot 'plot_data.dat' u 1:" << col(c, 3) << " w l lc rgb '#d62728' t 'nominal', '' u 1:"
      << col(c, 4) << " w l lc rgb '#2ca02c' t 'augmented'\n";
  }
  g << "unset multiplot\n";
  return g.str();
}

bool run_gnuplot(const std::string& dir) {
  const std::string cmd = "cd '" + dir + "' && gnuplot plots.gp > gnuplot.log 2>&1";
  return std::system(cmd.c_str()) == 0;
}

std::string markdown(const GapResult& r, bool plots) {
  std::ostringstream md;
  md << "# Model-gap report: " << r.nominal.name << "\n\n"
     << "Run `" << r.run_source << "`, model `" << r.nominal.source_file << "`.\n\n"
     << "**Verdict: " << verdict_name(r.verdict) << ".** " << r.summary << "\n\n";
  if (!r.named.empty()) {
    md << "## Named effects\n\n| effect | parameter | value | 1 sigma |\n|---|---|---|---|\n";
    for (const auto& e : r.named) {
      for (const auto& [k, v] : e.values) {
        md << "| " << e.name << " | " << k << " | " << fmt(v, 6) << " | "
           << fmt(e.sigmas.count(k) ? e.sigmas.at(k) : NAN, 2) << " |\n";
      }
    }
    md << "\nThe augmented model is `model_augmented.yaml` (the nominal model with these effects).\n\n";
  }
  if (r.verdict == Verdict::kUnexplained) {
    md << "## Unexplained residual\n\nNo candidate (single or pair) removed at least "
       << fmt(100.0 * r.options.min_explained, 3) << " % of the held-out residual with significant "
       << "parameters. Worst channel: `" << r.unexplained_channel << "`, character: "
       << r.unexplained_character.label;
    if (!r.unexplained_character.signal.empty()) {
      md << " (regressor " << r.unexplained_character.signal << ", R^2 = "
         << fmt(r.unexplained_character.r_squared, 3) << ")";
    }
    md << ".\n\n";
  }
  md << "## Gap before and after\n\n"
     << "| question | RMS position (m) | final position (m) | RMS heading (rad) | final heading (rad) |\n"
     << "|---|---|---|---|---|\n";
  for (const auto& p : r.pose_gaps) {
    md << "| " << question_name(p.question) << " | " << fmt(p.rms_position_m_before) << " -> "
       << fmt(p.rms_position_m_after) << " (" << ratio(p.rms_position_m_before, p.rms_position_m_after)
       << ") | " << fmt(p.final_position_m_before) << " -> " << fmt(p.final_position_m_after) << " | "
       << fmt(p.rms_heading_rad_before) << " -> " << fmt(p.rms_heading_rad_after) << " | "
       << fmt(p.final_heading_rad_before) << " -> " << fmt(p.final_heading_rad_after) << " |\n";
  }
  md << "\n| channel | unit | RMS before | RMS after | shrink | held-out whitened RMS before -> after | character (nominal) |\n"
     << "|---|---|---|---|---|---|---|\n";
  for (const auto& c : r.channels) {
    md << "| " << c.info.name << " | " << c.info.unit << " | " << fmt(c.rms_before) << " | "
       << fmt(c.rms_after) << " | " << ratio(c.rms_before, c.rms_after) << " | "
       << fmt(c.whitened_rms_validation_before, 3) << " -> " << fmt(c.whitened_rms_validation_after, 3)
       << " | " << c.character_before.label << " |\n";
  }
  if (plots) {
    md << "\n![trajectories](trajectory.png)\n\n![residuals](residuals.png)\n";
  } else {
    md << "\n(gnuplot was not available: no plots; the data are in plot_data.dat)\n";
  }
  md << "\n## Where the nominal model disagrees\n\n";
  for (const auto& c : r.channels) {
    if (c.windows.empty()) continue;
    md << "- `" << c.info.name << "`: residual grows ";
    for (std::size_t i = 0; i < c.windows.size() && i < 3; ++i) {
      const auto& w = c.windows[i];
      md << (i ? ", " : "") << fmt(w.start_s, 4) << "-" << fmt(w.end_s, 4) << " s ("
         << phase_name(w.dominant_phase) << ", +" << fmt(w.growth, 3) << " " << c.info.unit << ")";
    }
    md << "; " << c.character_before.label << ".\n";
  }
  md << "\nMotion phases (from the commands): ";
  double durations[4] = {0, 0, 0, 0};
  for (const auto& s : r.segments) durations[static_cast<int>(s.kind)] += s.end_s - s.start_s;
  for (int p = 0; p < 4; ++p) {
    md << (p ? ", " : "") << phase_name(static_cast<PhaseKind>(p)) << " " << fmt(durations[p], 4) << " s";
  }
  md << ".\n\n## Candidates (best BIC first)\n\n"
     << "| effects | parameters | delta BIC | explained (fit) | explained (held out) |\n|---|---|---|---|---|\n";
  for (const auto& c : r.candidates) {
    md << "| " << c.label() << " | ";
    for (std::size_t i = 0; i < c.param_names.size(); ++i) {
      md << (i ? ", " : "") << c.param_names[i] << " = " << fmt(c.values[i], 4) << " +- " << fmt(c.sigmas[i], 2);
    }
    md << " | " << fmt(c.delta_bic, 5) << " | " << fmt(c.explained_training, 4) << " | "
       << fmt(c.explained_validation, 4) << " |\n";
  }
  md << "\nSelection: an effect set is named when it removes at least "
     << fmt(100.0 * r.options.min_explained, 3) << " % of the held-out residual above the noise level (last "
     << fmt(100.0 * r.options.holdout_fraction, 3) << " % of the run), every parameter exceeds "
     << fmt(r.options.min_significance, 3) << " sigma, and (for a pair) the second effect removes "
     << fmt(100.0 * r.options.min_pair_gain, 3) << " % of what the best single leaves and lowers BIC by "
     << fmt(r.options.min_delta_bic, 3) << ". Nothing is named when the nominal held-out residual stays below "
     << fmt(r.options.min_gap_whitened_rms, 3) << " noise sigmas in every channel. Workflow time "
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
  save_robot_model(result.augmented, (d / "model_augmented.yaml").string());
  write_plot_data(result, (d / "plot_data.dat").string());
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
