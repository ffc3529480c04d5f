// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/cross_run.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "swivel/model_gap/fold_effects.hpp"
#include "swivel/model_gap/sensor_replay.hpp"
#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {

double median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

namespace {

// Weighted mean and its sigma of values with sigmas, leaving out index `skip` (none: size).
std::pair<double, double> weighted_mean(const std::vector<double>& v, const std::vector<double>& s,
                                        std::size_t skip) {
  double sw = 0.0;
  double swx = 0.0;
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (k == skip) continue;
    const double w = 1.0 / (s[k] * s[k]);
    sw += w;
    swx += w * v[k];
  }
  return {swx / sw, std::sqrt(1.0 / sw)};
}

std::vector<ParameterAgreement> agreement_of(const std::vector<FitRun>& fits) {
  std::map<std::string, ParameterAgreement> by_name;
  for (const FitRun& f : fits) {
    std::vector<FittedEffect> effects = f.named;
    effects.insert(effects.end(), f.calibrated.begin(), f.calibrated.end());
    for (const FittedEffect& e : effects) {
      for (std::size_t i = 0; i < e.keys.size(); ++i) {
        // What the run fixes of a parameter it cannot fix alone.
        const double sigma = std::isfinite(e.sigmas[i]) ? e.sigmas[i] : e.partial_sigmas[i];
        if (!(sigma > 0.0) || !std::isfinite(sigma)) continue;
        ParameterAgreement& a = by_name[(e.limits ? "limits." : e.name + ".") + e.keys[i]];
        a.runs.push_back(f.run);
        a.values.push_back(e.values[i]);
        a.sigmas.push_back(sigma);
      }
    }
  }
  std::vector<ParameterAgreement> out;
  for (auto& [name, a] : by_name) {
    a.name = name;
    const std::size_t n = a.values.size();
    std::tie(a.weighted_mean, a.sigma_of_mean) = weighted_mean(a.values, a.sigmas, n);
    for (std::size_t k = 0; k < n; ++k) {
      const double z = (a.values[k] - a.weighted_mean) / a.sigmas[k];
      a.chi_square += z * z;
    }
    a.dof = n > 0 ? n - 1 : 0;
    if (n > 1) {
      double in1 = 0.0;
      double in2 = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        const auto [m, sm] = weighted_mean(a.values, a.sigmas, k);
        const double z = std::abs(a.values[k] - m) / std::hypot(a.sigmas[k], sm);
        in1 += z <= 1.0 ? 1.0 : 0.0;
        in2 += z <= 2.0 ? 1.0 : 0.0;
      }
      a.within_1_sigma = in1 / static_cast<double>(n);
      a.within_2_sigma = in2 / static_cast<double>(n);
    }
    out.push_back(a);
  }
  return out;
}

std::string fmt(double v, int precision = 4) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

// The effects a run named or calibrated, as one label: "track_width+wheel_radius".
std::string effect_set(const FitRun& f) {
  std::vector<std::string> names;
  for (const std::vector<FittedEffect>* list : {&f.named, &f.calibrated}) {
    for (const FittedEffect& e : *list) names.push_back(e.limits ? "limits" : e.name);
  }
  std::sort(names.begin(), names.end());
  std::string label;
  for (const std::string& n : names) label += (label.empty() ? "" : "+") + n;
  return label;
}

std::string runs_text(std::size_t n) { return std::to_string(n) + (n == 1 ? " run" : " runs"); }

// A track fixed alone by runs turning both ways round: the track and a left/right radius
// difference (track_by_turn.hpp), pooled as such when the difference is significant at
// `min_z`. False: pool the track's weighted mean instead.
bool pool_track_by_turn(const RobotModel& nominal, const std::vector<FitRun>& runs, double min_z,
                        CrossRunResult& r) {
  if (nominal.drivetrain != DrivetrainKind::kDifferential ||
      effect_set(runs.front()) != "track_width")
    return false;
  std::vector<double> scales;
  std::vector<double> sigmas;
  std::vector<double> radii;
  for (const FitRun& f : runs) {
    const FittedEffect& e = f.named.empty() ? f.calibrated.front() : f.named.front();
    if (e.values.size() != 1 || !(e.sigmas[0] > 0.0) || !std::isfinite(e.sigmas[0])) continue;
    scales.push_back(e.values[0]);
    sigmas.push_back(e.sigmas[0]);
    radii.push_back(f.turn_radius_m);
  }
  r.track_by_turn = fit_track_by_turn(scales, sigmas, radii, nominal.differential.track_width_m);
  const TrackByTurn& t = r.track_by_turn;
  if (!t.fitted || std::abs(t.radius_difference) < min_z * t.radius_difference_sigma) return false;
  r.pooled.effects["track_width"]["scale"] = t.track_scale;
  r.pooled.effects["wheel_radius"]["left_scale"] = 1.0 - t.radius_difference;
  r.pooled.effects["wheel_radius"]["right_scale"] = 1.0 + t.radius_difference;
  r.pooled_from.push_back(
      "track_width.scale = " + fmt(t.track_scale, 6) + " +- " + fmt(t.track_scale_sigma, 2) +
      " and wheel_radius right " + fmt(1.0 + t.radius_difference, 6) + ", left " +
      fmt(1.0 - t.radius_difference, 6) + " (1 +- e, e = " + fmt(t.radius_difference, 3) + " +- " +
      fmt(t.radius_difference_sigma, 2) + "), from the tracks of " + runs_text(t.runs) +
      " against the radius each turned at (chi^2 " + fmt(t.chi_square, 3) + " for " +
      std::to_string(t.runs - 2) + " dof; one track for all: " + fmt(t.chi_square_one_track, 3) +
      ")");
  return true;
}

// The model fitted on all the runs. Each run fitted its effects beside each other, so a
// parameter is pooled only over runs that fixed the same set: a track fitted alone holds what
// wheel radii would take beside it, and the two pooled from different runs would count it
// twice. The set most runs fixed (two at least), each parameter at its weighted mean, or a
// track with the radius difference that runs turning both ways show.
void pool(const RobotModel& nominal, double min_z, CrossRunResult& r) {
  r.pooled = nominal;
  std::map<std::string, std::vector<FitRun>> by_set;
  for (const FitRun& f : r.fits) {
    if (const std::string set = effect_set(f); !set.empty()) by_set[set].push_back(f);
  }
  const std::vector<FitRun>* best = nullptr;
  for (const auto& [set, runs] : by_set) {
    if (best == nullptr || runs.size() > best->size()) best = &runs;
  }
  for (const auto& [set, runs] : by_set) {
    if (&runs == best && runs.size() >= 2 && set.find("limits") == std::string::npos) continue;
    r.pooled_left_out.push_back(set + ": " + runs_text(runs.size()) +
                                (&runs == best ? "" : ", not the set most runs fixed"));
  }
  if (best == nullptr || best->size() < 2 ||
      effect_set(best->front()).find("limits") != std::string::npos)
    return;
  if (pool_track_by_turn(nominal, *best, min_z, r)) return;
  for (const ParameterAgreement& a : agreement_of(*best)) {
    const std::size_t dot = a.name.find('.');
    r.pooled.effects[a.name.substr(0, dot)][a.name.substr(dot + 1)] = a.weighted_mean;
    r.pooled_from.push_back(a.name + " = " + fmt(a.weighted_mean, 6) + " +- " +
                            fmt(a.sigma_of_mean, 2) + " (" + runs_text(a.values.size()) + ")");
  }
}

}  // namespace

HeldOutGap held_out_gap(const RobotModel& model, const RunData& run, const GapOptions& options) {
  const SensorReplay sensors(model, run, options.window_s);
  if (sensors.windows().size() < 10) {
    throw std::invalid_argument("run " + run.source + " gives " +
                                std::to_string(sensors.windows().size()) +
                                " windows; the workflow needs at least 10");
  }
  const QuestionReplay replay = sensor_question_replay(sensors, model);
  // No candidates: only the motion capture's nuisances are fitted, for this model.
  const QuestionResult q =
      analyse_question(Question::kSensorToPose, model, replay, {}, options.question);
  std::vector<Pose2> path;
  sensors.path(sim::resolve_plant(model), sensors.truth(q.nuisance), path);
  const PoseGap g = compare_paths(Question::kSensorToPose, run, path, path);
  return {run.source, g.rms_position_m_before, g.rms_heading_rad_before};
}

CrossRunResult cross_validate(const RobotModel& nominal, const std::vector<RunData>& runs,
                              const GapOptions& options, const CrossRunProgress& progress) {
  CrossRunResult result;
  GapOptions sensor_only = options;
  sensor_only.sensor_only = true;
  const std::size_t n = runs.size();
  const std::size_t steps = 2 * n;
  std::size_t step = 0;
  const auto tell = [&](const std::string& what) {
    if (progress) progress(++step, steps, what);
  };
  // The nominal model's gap on every run (the reference of every ratio).
  std::vector<double> nominal_gap(n, std::numeric_limits<double>::quiet_NaN());
  std::vector<char> usable(n, 0);
  for (std::size_t k = 0; k < n; ++k) {
    try {
      nominal_gap[k] = held_out_gap(nominal, runs[k], options).rms_position_m;
      usable[k] = 1;
    } catch (const std::exception& e) {
      result.skipped.push_back(runs[k].source + ": " + e.what());
    }
    tell("nominal gap of " + runs[k].source);
  }
  std::vector<double> ratios;
  std::vector<double> ratios_named;
  std::vector<double> nominal_named;
  std::vector<double> fitted_named;
  const auto session = [&runs](std::size_t k) {
    return std::filesystem::path(runs[k].source).parent_path().string();
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (usable[i] == 0) {
      tell("skipped " + runs[i].source);
      continue;
    }
    const GapResult fitted = analyse_gap(nominal, runs[i], sensor_only);
    FitRun f;
    f.run = runs[i].source;
    f.verdict = fitted.sensor.verdict;
    f.summary = fitted.sensor.summary;
    f.named = fitted.sensor.named;
    f.calibrated = fitted.sensor.calibrated;
    f.truth = truth_nuisance_lines(fitted);
    f.fitted = fitted.sensor.verdict != Verdict::kUnexplained ? fitted.sensor.augmented : nominal;
    f.turn_radius_m = turn_radius_m(nominal, runs[i], options.window_s);
    const bool changed = !f.named.empty() || !f.calibrated.empty();
    if (f.verdict == Verdict::kUnexplained) ++result.unexplained;
    if (f.verdict == Verdict::kNamed) ++result.named;
    if (f.verdict == Verdict::kNoSignificantGap) ++result.no_gap;
    if (!f.calibrated.empty()) ++result.calibrated;
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i || usable[j] == 0 || session(j) != session(i)) continue;
      // A run that changed nothing predicts the others exactly as the nominal model does.
      const double gap =
          changed ? held_out_gap(f.fitted, runs[j], options).rms_position_m : nominal_gap[j];
      f.others.push_back(runs[j].source);
      f.nominal_rms_m.push_back(nominal_gap[j]);
      f.fitted_rms_m.push_back(gap);
      f.ratio.push_back(gap / nominal_gap[j]);
      ratios.push_back(f.ratio.back());
      if (changed) {
        ratios_named.push_back(f.ratio.back());
        nominal_named.push_back(nominal_gap[j]);
        fitted_named.push_back(gap);
      }
    }
    result.fits.push_back(std::move(f));
    tell("fitted on " + runs[i].source);
  }
  result.pairs = ratios.size();
  result.median_ratio = median(ratios);
  result.pairs_named = ratios_named.size();
  result.median_ratio_named = median(ratios_named);
  result.median_nominal_rms_m = median(nominal_named);
  result.median_fitted_rms_m = median(fitted_named);
  result.agreement = agreement_of(result.fits);
  pool(nominal, options.question.min_z_calibrate, result);
  return result;
}

namespace {

nlohmann::json effects_json(const std::vector<FittedEffect>& effects) {
  using nlohmann::json;
  json out = json::array();
  for (const FittedEffect& e : effects) {
    for (std::size_t i = 0; i < e.keys.size(); ++i) {
      out.push_back({{"parameter", e.name + "." + e.keys[i]},
                     {"value", e.values[i]},
                     {"sigma", std::isfinite(e.sigmas[i]) ? json(e.sigmas[i]) : json(nullptr)}});
    }
  }
  return out;
}

// "effect.key = value +- sigma, ..." ("*": not observable alone).
std::string effects_text(const std::vector<FittedEffect>& effects) {
  std::string text;
  for (const FittedEffect& e : effects) {
    for (std::size_t i = 0; i < e.keys.size(); ++i) {
      text += (text.empty() ? "" : ", ") + e.name + "." + e.keys[i] + " = " + fmt(e.values[i], 6) +
              " +- " + (std::isfinite(e.sigmas[i]) ? fmt(e.sigmas[i], 2) : std::string("*"));
    }
  }
  return text;
}

nlohmann::json fit_run_json(const FitRun& f) {
  using nlohmann::json;
  json others = json::array();
  for (std::size_t k = 0; k < f.others.size(); ++k) {
    others.push_back({{"run", f.others[k]},
                      {"nominal_rms_position_m", f.nominal_rms_m[k]},
                      {"fitted_rms_position_m", f.fitted_rms_m[k]},
                      {"ratio", f.ratio[k]}});
  }
  return {{"run", f.run},
          {"verdict", verdict_name(f.verdict)},
          {"named", effects_json(f.named)},
          {"calibrated", effects_json(f.calibrated)},
          {"motion_capture", f.truth},
          {"turn_radius_m", std::isfinite(f.turn_radius_m) ? json(f.turn_radius_m) : json(nullptr)},
          {"median_ratio", median(f.ratio)},
          {"others", others}};
}

nlohmann::json cross_run_json(const CrossRunResult& r, const RobotModel& nominal) {
  using nlohmann::json;
  json j;
  j["robot"] = nominal.name;
  j["model"] = nominal.source_file;
  j["median_ratio"] = r.median_ratio;
  j["pairs"] = r.pairs;
  j["pairs_named"] = r.pairs_named;
  j["median_ratio_named"] = r.median_ratio_named;
  j["median_nominal_rms_position_m"] = r.median_nominal_rms_m;
  j["median_fitted_rms_position_m"] = r.median_fitted_rms_m;
  j["verdicts"] = {{"named", r.named},
                   {"no significant gap", r.no_gap},
                   {"of which calibrated", r.calibrated},
                   {"unexplained residual", r.unexplained}};
  j["unexplained"] = r.unexplained;
  j["skipped"] = r.skipped;
  json fits = json::array();
  for (const FitRun& f : r.fits) fits.push_back(fit_run_json(f));
  j["fits"] = fits;
  json agreement = json::array();
  for (const ParameterAgreement& a : r.agreement) {
    agreement.push_back({{"parameter", a.name},
                         {"runs", a.runs},
                         {"values", a.values},
                         {"sigmas", a.sigmas},
                         {"weighted_mean", a.weighted_mean},
                         {"sigma_of_mean", a.sigma_of_mean},
                         {"chi_square", a.chi_square},
                         {"dof", a.dof},
                         {"within_1_sigma", a.within_1_sigma},
                         {"within_2_sigma", a.within_2_sigma}});
  }
  j["agreement"] = agreement;
  j["pooled"] = {{"from", r.pooled_from}, {"left_out", r.pooled_left_out}};
  if (r.track_by_turn.fitted) {
    const TrackByTurn& t = r.track_by_turn;
    j["track_by_turn"] = {{"track_scale", t.track_scale},
                          {"track_scale_sigma", t.track_scale_sigma},
                          {"radius_difference", t.radius_difference},
                          {"radius_difference_sigma", t.radius_difference_sigma},
                          {"chi_square", t.chi_square},
                          {"chi_square_one_track", t.chi_square_one_track},
                          {"runs", t.runs}};
  }
  return j;
}

void write_cross_run_markdown(const CrossRunResult& r, const RobotModel& nominal,
                              std::ostream& md) {
  md << "# Across runs: " << nominal.name << "\n\n"
     << "Each run in turn is analysed (sensor to pose); what it names or calibrates is replayed on "
        "every other "
        "run beside the nominal model, each run with its own motion-capture nuisances fitted. "
        "The ratio is the whole-run RMS position gap with the fitted model over the gap with the "
        "nominal one (below 1: the fitted model predicts a run it has not seen better).\n\n"
     << "Median ratio over " << r.pairs << " (fit run, other run of its session) pairs: **"
     << fmt(r.median_ratio, 3) << "**; over the " << r.pairs_named
     << " pairs whose fit run named or calibrated something: **" << fmt(r.median_ratio_named, 3)
     << "** (RMS position gap " << fmt(1000.0 * r.median_nominal_rms_m, 3) << " mm nominal, "
     << fmt(1000.0 * r.median_fitted_rms_m, 3)
     << " mm fitted, medians). Sensor verdicts: " << r.named << " named, " << r.no_gap
     << " no significant gap (" << r.calibrated << " of them calibrated), " << r.unexplained
     << " unexplained, of " << r.fits.size() << ".\n\n"
     << "| fitted on | verdict | named | calibrated | median ratio on the others |\n"
     << "|---|---|---|---|---|\n";
  for (const FitRun& f : r.fits) {
    md << "| " << f.run << " | " << verdict_name(f.verdict) << " | " << effects_text(f.named)
       << " | " << effects_text(f.calibrated) << " | "
       << (f.ratio.empty() ? std::string("-") : fmt(median(f.ratio), 3)) << " |\n";
  }
  md << "\n## Agreement of the named and calibrated values\n\n"
     << "| parameter | runs | weighted mean | sigma of mean | chi^2 / dof | within 1 / 2 sigma "
        "of the others |\n|---|---|---|---|---|---|\n";
  for (const ParameterAgreement& a : r.agreement) {
    md << "| " << a.name << " | " << a.values.size() << " | " << fmt(a.weighted_mean, 6) << " | "
       << fmt(a.sigma_of_mean, 2) << " | " << fmt(a.chi_square, 3) << " / " << a.dof << " | "
       << fmt(100.0 * a.within_1_sigma, 3) << " % / " << fmt(100.0 * a.within_2_sigma, 3)
       << " % |\n";
  }
  md << "\n## The model fitted on all the runs: `model_pooled.yaml`\n\n"
     << "The set of effects most runs named or calibrated (two at least), each parameter at its "
        "weighted mean over those runs: runs that fixed other sets fitted their parameters beside "
        "other effects, and pooling across sets would count an effect twice (a track fitted "
        "alone holds what wheel radii take beside it). Judge it on runs it was not fitted on "
        "with `swivel-lab gap-judge`.\n\n";
  for (const std::string& line : r.pooled_from) md << "- " << line << "\n";
  for (const std::string& line : r.pooled_left_out) md << "- left out: " << line << "\n";
  if (!r.skipped.empty()) {
    md << "\n## Runs not used\n\n";
    for (const std::string& s : r.skipped) md << "- " << s << "\n";
  }
}

}  // namespace

void write_cross_run_report(const CrossRunResult& r, const RobotModel& nominal,
                            const std::string& dir) {
  std::filesystem::create_directories(dir);
  std::ofstream js(dir + "/cross_run.json");
  js << cross_run_json(r, nominal).dump(2) << "\n";
  if (!js) throw std::runtime_error("cannot write " + dir + "/cross_run.json");
  std::ofstream md(dir + "/cross_run.md");
  write_cross_run_markdown(r, nominal, md);
  if (!md) throw std::runtime_error("cannot write " + dir + "/cross_run.md");
  write_folded_model(r.pooled,
                     nominal.name + ", fitted on " + std::to_string(r.fits.size()) +
                         " runs together (swivel-lab gap-cross: the set of effects most runs "
                         "named or calibrated, each parameter at its weighted mean over them)",
                     dir + "/model_pooled.yaml");
}

}  // namespace swivel::model_gap
