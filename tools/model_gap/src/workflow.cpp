#include "swivel/model_gap/workflow.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "swivel/model_gap/replay.hpp"

namespace swivel::model_gap {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// White-noise level of a residual from its second differences: a smooth systematic
// residual has nearly none, white noise of sigma has 6 sigma^2 (MAD for robustness).
double noise_sigma(const std::vector<double>& r) {
  std::vector<double> d2;
  for (std::size_t k = 2; k < r.size(); ++k) {
    const double v = r[k] - 2.0 * r[k - 1] + r[k - 2];
    if (std::isfinite(v)) d2.push_back(v);
  }
  if (d2.size() < 10) return kNaN;
  const double m = median(d2);
  for (auto& v : d2) v = std::abs(v - m);
  return 1.4826 * median(d2) / std::sqrt(6.0);
}

// The model's own sensor noise bounds the whitening scale from below: a residual smaller
// than the sensor can resolve is not evidence (and quantized encoders defeat the MAD).
double sigma_floor(ChannelKind kind, const SensorParams& sensors) {
  constexpr double kTwoPi = 2.0 * 3.14159265358979323846;
  const double sqrt12 = std::sqrt(12.0);
  double declared = 0.0;
  switch (kind) {
    case ChannelKind::kPosition:
      declared = sensors.motion_capture.position_noise_m;
      break;
    case ChannelKind::kHeading:
      declared = sensors.motion_capture.yaw_noise_rad;
      break;
    case ChannelKind::kWheelAngle:
      declared = kTwoPi / sensors.wheel_encoder_counts_per_rev / sqrt12;
      break;
    case ChannelKind::kSteerAngle:
      declared = kTwoPi / sensors.steering_encoder_counts_per_rev / sqrt12;
      break;
    case ChannelKind::kYawRate:
      declared = sensors.gyro.noise_rad_s;
      break;
  }
  return std::max(declared, 1e-6);
}

// Row layout of the fitted residual vector: channel-major, decimated, measured samples only.
struct Rows {
  std::vector<std::size_t> channel;
  std::vector<std::size_t> sample;
  std::vector<double> sigma;
  std::vector<char> training;
};

struct Context {
  const RobotModel* nominal = nullptr;
  const Replay* replay = nullptr;
  Rows rows;
  std::size_t limit = 0;  // replay samples [0, limit); later rows read as NaN
  mutable ChannelSet scratch;
  mutable RobotModel model;
};

void apply_params(RobotModel& model, const RobotModel& nominal,
                  const std::vector<const CandidateEffect*>& effects, std::span<const double> theta) {
  model.effects = nominal.effects;
  std::size_t i = 0;
  for (const auto* e : effects) {
    auto& params = model.effects[e->effect];
    for (const auto& p : e->params) params[p.name] = theta[i++];
  }
}

bool fill_rows(const Context& ctx, std::vector<double>& r) {
  const ChannelSet& meas = ctx.replay->measured();
  r.resize(ctx.rows.channel.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    const std::size_t c = ctx.rows.channel[i];
    const std::size_t k = ctx.rows.sample[i];
    if (k >= ctx.limit) {
      r[i] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    const double p = ctx.scratch.values[c][k];
    if (!std::isfinite(p)) return false;  // a replay that diverged is not a candidate
    r[i] = residual_at(meas.info[c], meas.values[c][k], p) / ctx.rows.sigma[i];
  }
  return true;
}

FitProblem make_problem(const Context& ctx, const std::vector<const CandidateEffect*>& effects) {
  FitProblem p;
  p.row_count = ctx.rows.channel.size();
  p.is_training = ctx.rows.training;
  p.row_group = ctx.rows.channel;
  p.residuals = [&ctx, effects](std::span<const double> theta, std::vector<double>& r) {
    apply_params(ctx.model, *ctx.nominal, effects, theta);
    ctx.replay->predict(ctx.model, ctx.scratch, ctx.limit);
    return fill_rows(ctx, r);
  };
  return p;
}

double rms_of(const std::vector<double>& r) {
  double s = 0.0;
  double n = 0.0;
  for (double v : r) {
    if (!std::isfinite(v)) continue;
    s += v * v;
    n += 1.0;
  }
  return n > 0.0 ? std::sqrt(s / n) : kNaN;
}

double last_finite(const std::vector<double>& r) {
  for (auto it = r.rbegin(); it != r.rend(); ++it) {
    if (std::isfinite(*it)) return *it;
  }
  return kNaN;
}

// Share of the nominal residual above the noise level that a candidate removes. Whitened
// rows of pure noise sum to about one each, so n rows leave rss - n to explain; a weak
// effect is then judged on what it can explain, not on the noise it cannot.
double explained(double rss_nominal, double rss, std::size_t n) {
  const double excess = std::max(rss_nominal - static_cast<double>(n), 1e-9 * rss_nominal);
  return std::min(1.0, (rss_nominal - rss) / std::max(excess, 1e-300));
}

// Largest per-channel whitened RMS over the held-out rows.
double worst_validation_rms(const Rows& rows, const std::vector<double>& r, std::size_t channels) {
  std::vector<double> sum(channels, 0.0);
  std::vector<double> count(channels, 0.0);
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (rows.training[i] || !std::isfinite(r[i])) continue;
    sum[rows.channel[i]] += r[i] * r[i];
    count[rows.channel[i]] += 1.0;
  }
  double worst = 0.0;
  for (std::size_t c = 0; c < channels; ++c) {
    if (count[c] > 0.0) worst = std::max(worst, std::sqrt(sum[c] / count[c]));
  }
  return worst;
}

std::string fmt(double v, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

}  // namespace

std::string CandidateScore::label() const {
  std::string s;
  for (const auto& e : effects) s += (s.empty() ? "" : " + ") + e;
  return s.empty() ? "nominal" : s;
}

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::kNoSignificantGap:
      return "no significant gap";
    case Verdict::kNamed:
      return "named";
    case Verdict::kUnexplained:
      return "unexplained residual";
  }
  return "unknown";
}

GapResult analyse_gap(const RobotModel& nominal, const RunData& run, const GapOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  GapResult result;
  result.options = options;
  result.nominal = nominal;
  result.augmented = nominal;
  result.run_source = run.source;
  result.t_s = run.t_s;

  Replay replay(nominal, run);
  result.measured = replay.measured();
  replay.predict(nominal, result.before);
  const ChannelSet& meas = result.measured;
  const std::size_t n = run.size();
  const std::size_t channels = meas.channel_count();
  const auto res_before = residuals(meas, result.before);

  const double t0 = run.t_s.front();
  const double t_end = run.t_s.back();
  result.holdout_start_s = t0 + (1.0 - options.holdout_fraction) * (t_end - t0);
  const double dt = (t_end - t0) / static_cast<double>(n - 1);

  // Noise levels; dead-reckoned pose also carries the integrated gyro noise, which grows
  // with time (heading) and with distance travelled times heading error (position).
  std::vector<double> sigma(channels);
  for (std::size_t c = 0; c < channels; ++c) {
    const double s = noise_sigma(res_before[c]);
    sigma[c] = std::max(std::isfinite(s) ? s : 0.0, sigma_floor(meas.info[c].kind, nominal.sensors));
  }
  const std::size_t gyro_channel = meas.find("simulation.gyro_radps");
  const double gyro_sigma = gyro_channel < channels ? sigma[gyro_channel] : 0.0;
  const CommandSeries cmd = run.commands();
  const MotionSignals signals = motion_signals(cmd);

  double start_yaw_var = 0.0;
  {
    double samples = 0.0;
    for (std::size_t k = 0; k < n && run.t_s[k] - t0 <= 1.0; ++k) {
      if (run.cmd_vx_mps[k] != 0.0 || run.cmd_vy_mps[k] != 0.0 || run.cmd_wz_radps[k] != 0.0) break;
      if (std::isfinite(run.truth_yaw_rad[k])) samples += 1.0;
    }
    const double yaw_sigma = std::max(nominal.sensors.motion_capture.yaw_noise_rad, 1e-6);
    start_yaw_var = yaw_sigma * yaw_sigma / std::max(samples, 1.0);
  }

  Context ctx;
  ctx.nominal = &nominal;
  ctx.replay = &replay;
  ctx.model = nominal;
  ctx.limit = n;
  ctx.scratch = result.before;
  const auto stride = static_cast<std::size_t>(
      std::max(1.0, std::round(1.0 / (dt * options.fit_rate_hz))));
  for (std::size_t c = 0; c < channels; ++c) {
    for (std::size_t k = 0; k < n; k += stride) {
      if (!std::isfinite(meas.values[c][k])) continue;
      double s2 = sigma[c] * sigma[c];
      const double d2 = signals.distance_m[k] * signals.distance_m[k];
      if (meas.info[c].question == Question::kSensorToPose) {
        const double walk = gyro_sigma * gyro_sigma * dt * signals.time_s[k];
        s2 += meas.info[c].kind == ChannelKind::kHeading ? walk : walk * d2 / 3.0;
      }
      // Replayed poses start from a heading known only to the motion capture's averaged
      // noise; that error turns every later position by the same small angle.
      if (meas.info[c].kind == ChannelKind::kPosition) s2 += start_yaw_var * d2;
      ctx.rows.channel.push_back(c);
      ctx.rows.sample.push_back(k);
      ctx.rows.sigma.push_back(std::sqrt(s2));
      ctx.rows.training.push_back(run.t_s[k] < result.holdout_start_s ? 1 : 0);
    }
  }

  // Nominal score and the worst channel on the held-out part.
  const FitProblem nominal_problem = make_problem(ctx, {});
  const FitOutcome base = score(nominal_problem, {});
  if (!base.ok) throw std::runtime_error("the nominal model cannot replay run " + run.source);
  std::vector<double> val_sum(channels, 0.0);
  std::vector<double> val_count(channels, 0.0);
  for (std::size_t i = 0; i < base.residuals.size(); ++i) {
    if (ctx.rows.training[i] || !std::isfinite(base.residuals[i])) continue;
    val_sum[ctx.rows.channel[i]] += base.residuals[i] * base.residuals[i];
    val_count[ctx.rows.channel[i]] += 1.0;
  }
  for (std::size_t c = 0; c < channels; ++c) {
    const double w = val_count[c] > 0.0 ? std::sqrt(val_sum[c] / val_count[c]) : 0.0;
    if (w > result.worst_whitened_rms_before) {
      result.worst_whitened_rms_before = w;
      result.worst_channel_before = meas.info[c].name;
    }
  }
  const bool gap = result.worst_whitened_rms_before >= options.min_gap_whitened_rms;

  // Candidates: every library effect alone, then pairs of the best singles.
  const std::vector<CandidateEffect> library = candidate_library(nominal);
  struct Fitted {
    std::vector<const CandidateEffect*> effects;
    FitOutcome fit;
    CandidateScore score;
  };
  std::vector<Fitted> fitted;
  // Fits replay only the part they fit (the training part, or a shorter screening window);
  // every candidate is then scored on the whole run.
  std::size_t training_end = 0;
  while (training_end < n && run.t_s[training_end] < result.holdout_start_s) ++training_end;
  const auto evaluate = [&](std::vector<const CandidateEffect*> effects,
                            const std::vector<double>& initial, std::size_t fit_end,
                            const FitOptions& fit_options) {
    std::vector<ParamSpec> specs;
    std::size_t i = 0;
    for (const auto* e : effects) {
      for (auto p : e->params) {
        p.initial = initial.empty() ? p.initial : initial[i];
        p.name = e->effect + "." + p.name;
        specs.push_back(p);
        ++i;
      }
    }
    Fitted f;
    f.effects = effects;
    ctx.limit = fit_end;
    const FitOutcome partial = fit(make_problem(ctx, effects), specs, fit_options);
    ctx.limit = n;
    f.fit = score(make_problem(ctx, effects), partial.values);
    f.fit.ok = f.fit.ok && partial.ok;
    f.fit.sigmas = partial.sigmas;
    f.fit.covariance = partial.covariance;
    f.fit.iterations = partial.iterations;
    auto& s = f.score;
    s.ok = f.fit.ok;
    for (const auto* e : effects) s.effects.push_back(e->effect);
    for (const auto& p : specs) s.param_names.push_back(p.name);
    s.values = f.fit.values;
    s.sigmas = f.fit.sigmas;
    s.iterations = f.fit.iterations;
    if (f.fit.ok) {
      s.bic = f.fit.bic;
      s.delta_bic = f.fit.bic - base.bic;
      s.explained_training = explained(base.rss_training, f.fit.rss_training, base.n_training);
      s.explained_validation = explained(base.rss_validation, f.fit.rss_validation, base.n_validation);
    } else {
      s.bic = std::numeric_limits<double>::infinity();
      s.delta_bic = s.bic;
    }
    fitted.push_back(std::move(f));
  };
  if (gap) {
    // Long runs: screen every effect on a shorter window first and refit only the most
    // promising ones on the whole training part.
    std::size_t screen_end = 0;
    while (screen_end < n && run.t_s[screen_end] - t0 < options.screening_window_s) ++screen_end;
    const bool screen = screen_end * 3 < training_end * 2;
    for (const auto& e : library) evaluate({&e}, {}, screen ? screen_end : training_end, options.fit);
    std::vector<std::size_t> order(fitted.size());
    std::iota(order.begin(), order.end(), 0U);
    const auto by_bic = [&](std::size_t a, std::size_t b) {
      return fitted[a].score.bic < fitted[b].score.bic;
    };
    std::sort(order.begin(), order.end(), by_bic);
    if (screen) {
      const std::size_t refit = std::min(options.refit_count, order.size());
      for (std::size_t i = 0; i < refit; ++i) {
        const Fitted& f = fitted[order[i]];
        if (!f.fit.ok) continue;
        const std::vector<double> start = f.fit.values;
        // From the screening optimum a few iterations suffice.
        FitOptions refit_options = options.fit;
        refit_options.max_iterations = std::min(refit_options.max_iterations, 8);
        evaluate(f.effects, start, training_end, refit_options);
        fitted[order[i]] = std::move(fitted.back());
        fitted.pop_back();
      }
      order.resize(fitted.size());
      std::iota(order.begin(), order.end(), 0U);
      std::sort(order.begin(), order.end(), by_bic);
    }
    // A pair is only worth fitting when the best single leaves a significant gap behind.
    std::size_t pool = std::min(options.pair_pool, order.size());
    if (!order.empty() && fitted[order[0]].fit.ok &&
        worst_validation_rms(ctx.rows, fitted[order[0]].fit.residuals, channels) <
            options.min_gap_whitened_rms) {
      pool = 0;
    }
    for (std::size_t a = 0; a < pool; ++a) {
      for (std::size_t b = a + 1; b < pool; ++b) {
        const Fitted fa = fitted[order[a]];
        const Fitted fb = fitted[order[b]];
        if (!fa.fit.ok || !fb.fit.ok) continue;
        std::vector<double> init = fa.fit.values;
        init.insert(init.end(), fb.fit.values.begin(), fb.fit.values.end());
        evaluate({fa.effects[0], fb.effects[0]}, init, training_end, options.fit);
      }
    }
  }
  std::sort(fitted.begin(), fitted.end(),
            [](const Fitted& a, const Fitted& b) { return a.score.bic < b.score.bic; });
  for (const auto& f : fitted) result.candidates.push_back(f.score);

  // Selection: the best single, upgraded to a pair only when the second effect earns it.
  // Every effect of a selection must have moved from its identity values by
  // min_significance standard deviations, jointly (Mahalanobis distance over its own
  // parameters): per-module effects can have correlated parameters none of which is
  // significant alone.
  const auto significant = [&](const Fitted& f) {
    if (!f.fit.ok || f.fit.covariance.empty()) return false;
    const std::size_t p = f.fit.values.size();
    std::size_t first = 0;
    for (const auto* e : f.effects) {
      const auto m = static_cast<Eigen::Index>(e->params.size());
      Eigen::MatrixXd cov(m, m);
      Eigen::VectorXd moved(m);
      for (Eigen::Index a = 0; a < m; ++a) {
        moved(a) = f.fit.values[first + static_cast<std::size_t>(a)] - e->identity[static_cast<std::size_t>(a)];
        for (Eigen::Index b = 0; b < m; ++b) {
          cov(a, b) = f.fit.covariance[(first + static_cast<std::size_t>(a)) * p + first + static_cast<std::size_t>(b)];
        }
      }
      if (!cov.allFinite()) return false;
      const double distance2 = moved.dot(cov.completeOrthogonalDecomposition().solve(moved));
      if (!(distance2 >= options.min_significance * options.min_significance)) return false;
      first += e->params.size();
    }
    return true;
  };
  const auto explains = [&](const Fitted& f) {
    return f.fit.ok && f.score.explained_validation >= options.min_explained &&
           f.score.explained_training >= options.min_explained &&
           f.score.delta_bic <= -options.min_delta_bic && significant(f);
  };
  const Fitted* chosen = nullptr;
  for (const auto& f : fitted) {
    if (f.effects.size() == 1 && f.fit.ok) {
      chosen = &f;
      break;
    }
  }
  if (chosen != nullptr) {
    for (const auto& f : fitted) {
      if (f.effects.size() != 2 || !f.fit.ok || !significant(f)) continue;
      const bool contains = f.effects[0] == chosen->effects[0] || f.effects[1] == chosen->effects[0];
      const double left = std::max(chosen->fit.rss_validation, 1e-300);
      const bool gains = f.fit.rss_validation <= (1.0 - options.min_pair_gain) * left &&
                         f.fit.rss_training <= (1.0 - options.min_pair_gain) * chosen->fit.rss_training &&
                         f.score.bic <= chosen->score.bic - options.min_delta_bic;
      // A pair that does not contain the best single may still win when it explains far more.
      if (gains && (contains || explains(f))) {
        chosen = &f;
        break;
      }
    }
  }
  if (!gap) {
    result.verdict = Verdict::kNoSignificantGap;
    result.summary = "The nominal model agrees with the run to within the sensor noise (worst channel " +
                     result.worst_channel_before + " at " + fmt(result.worst_whitened_rms_before) +
                     " noise sigmas on the held-out part); no effect is named.";
  } else if (chosen != nullptr && explains(*chosen)) {
    result.verdict = Verdict::kNamed;
    std::size_t i = 0;
    for (const auto* e : chosen->effects) {
      FittedEffect fe;
      fe.name = e->effect;
      for (const auto& p : e->params) {
        fe.values[p.name] = chosen->fit.values[i];
        fe.sigmas[p.name] = chosen->fit.sigmas[i];
        ++i;
      }
      result.named.push_back(fe);
      result.augmented.effects[fe.name] = fe.values;
    }
    result.summary = "Named " + chosen->score.label() + ": it removes " +
                     fmt(100.0 * chosen->score.explained_validation, 4) +
                     " % of the held-out residual (worst nominal channel " + result.worst_channel_before +
                     ").";
  } else {
    result.verdict = Verdict::kUnexplained;
  }

  replay.predict(result.augmented, result.after);
  const auto res_after = residuals(meas, result.after);

  // Per-channel report.
  const auto phases = classify_phases(cmd);
  result.segments = phase_segments(phases, run.t_s);
  std::vector<double> val_sum_after(channels, 0.0);
  {
    // Whitened held-out RMS after, on the same rows.
    std::vector<double> r;
    ctx.scratch = result.after;
    fill_rows(ctx, r);
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (!ctx.rows.training[i] && std::isfinite(r[i])) val_sum_after[ctx.rows.channel[i]] += r[i] * r[i];
    }
  }
  double worst_after = 0.0;
  std::size_t worst_after_channel = 0;
  for (std::size_t c = 0; c < channels; ++c) {
    ChannelReport cr;
    cr.info = meas.info[c];
    cr.noise_sigma = sigma[c];
    cr.rms_before = rms_of(res_before[c]);
    cr.rms_after = rms_of(res_after[c]);
    cr.final_before = last_finite(res_before[c]);
    cr.final_after = last_finite(res_after[c]);
    cr.whitened_rms_validation_before = val_count[c] > 0.0 ? std::sqrt(val_sum[c] / val_count[c]) : kNaN;
    cr.whitened_rms_validation_after = val_count[c] > 0.0 ? std::sqrt(val_sum_after[c] / val_count[c]) : kNaN;
    cr.character_before = characterise(res_before[c], result.before.values[c], cr.info, signals);
    cr.character_after = characterise(res_after[c], result.after.values[c], cr.info, signals);
    cr.windows = growth_windows(res_before[c], run.t_s, phases, 2.0 * sigma[c]);
    cr.phases = phase_stats(res_before[c], result.segments);
    if (cr.whitened_rms_validation_after > worst_after) {
      worst_after = cr.whitened_rms_validation_after;
      worst_after_channel = c;
    }
    result.channels.push_back(std::move(cr));
  }
  if (result.verdict == Verdict::kUnexplained) {
    const auto& worst = result.channels[worst_after_channel];
    result.unexplained_channel = worst.info.name;
    result.unexplained_character = worst.character_before;
    const std::string best = result.candidates.empty() ? "none" : result.candidates.front().label();
    const double best_explained =
        result.candidates.empty() ? 0.0 : result.candidates.front().explained_validation;
    result.summary = "Unexplained residual: no library effect explains the gap (best candidate " + best +
                     " removes " + fmt(100.0 * best_explained, 3) + " % of the held-out residual). Worst channel " +
                     worst.info.name + ", " + worst.character_before.label + ".";
  }

  // Pose gaps per question.
  for (Question q : {Question::kSensorToPose, Question::kCommandToPose}) {
    const std::string prefix = q == Question::kSensorToPose ? "dead_reckoning." : "simulation.";
    const std::size_t cx = meas.find(prefix + "x_m");
    const std::size_t cy = meas.find(prefix + "y_m");
    const std::size_t cyaw = meas.find(prefix + "yaw_rad");
    if (cx >= channels || cy >= channels || cyaw >= channels) continue;
    PoseGap pg;
    pg.question = q;
    const auto pos = [&](const std::vector<std::vector<double>>& r) {
      std::vector<double> d(n);
      for (std::size_t k = 0; k < n; ++k) d[k] = std::hypot(r[cx][k], r[cy][k]);
      return d;
    };
    const auto pb = pos(res_before);
    const auto pa = pos(res_after);
    pg.rms_position_m_before = rms_of(pb);
    pg.rms_position_m_after = rms_of(pa);
    pg.final_position_m_before = last_finite(pb);
    pg.final_position_m_after = last_finite(pa);
    pg.rms_heading_rad_before = rms_of(res_before[cyaw]);
    pg.rms_heading_rad_after = rms_of(res_after[cyaw]);
    pg.final_heading_rad_before = std::abs(last_finite(res_before[cyaw]));
    pg.final_heading_rad_after = std::abs(last_finite(res_after[cyaw]));
    result.pose_gaps.push_back(pg);
  }
  result.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace swivel::model_gap
