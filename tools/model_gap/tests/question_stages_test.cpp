// SPDX-License-Identifier: Apache-2.0
// The question's selection and verdict stages (src/question_stages.hpp) on hand-made fits:
// which single effect is chosen, when a pair replaces it, which misfit makes the residual
// unexplained, and what each verdict says.

#include "question_stages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

namespace swivel::model_gap::detail {
namespace {

// One parameter "<name>.k" with identity 0 and `resolution` (fit units).
Candidate candidate(const std::string& name, double resolution = 0.0) {
  Candidate c;
  c.name = name;
  c.keys = {"k"};
  ParamSpec p;
  p.name = name + ".k";
  c.params = {p};
  c.identity = {0.0};
  c.inverse = {0};
  c.resolution = {resolution};
  c.relative_resolution = {0.0};
  return c;
}

Fitted fitted(const std::vector<const Candidate*>& effects, double bic, double z, double size) {
  Fitted f;
  f.effects = effects;
  f.fit.ok = true;
  f.fit.bic = bic;
  f.fit.rss = 10.0;
  f.fit.n = 100;
  for (std::size_t e = 0; e < effects.size(); ++e) {
    f.fit.values.push_back(1.0);
    f.fit.sigmas.push_back(0.01);
    f.z.push_back(z);
    f.size.push_back(size);
  }
  f.rss_reference = 20.0;
  f.bic_reference = 0.0;
  return f;
}

MisfitTest misfit(const std::string& test, double z, double size) {
  MisfitTest m;
  m.test = test;
  m.channel = "dx";
  m.label = test + " pattern";
  m.z = z;
  m.size = size;
  return m;
}

TEST(QuestionSelection, SignificantNeedsSizeSignificanceAndResolution) {
  const QuestionOptions options;
  const Candidate sharp = candidate("sharp");
  const Candidate blurred = candidate("blurred", 1.0);  // as wide as the fitted change
  EXPECT_TRUE(significant(fitted({&sharp}, -50.0, 8.0, 2.0), options));
  EXPECT_FALSE(significant(fitted({&sharp}, -50.0, 4.9, 2.0), options));
  EXPECT_FALSE(significant(fitted({&sharp}, -50.0, 8.0, 0.4), options));
  EXPECT_FALSE(significant(fitted({&blurred}, -50.0, 8.0, 2.0), options));
  Fitted failed = fitted({&sharp}, -50.0, 8.0, 2.0);
  failed.fit.ok = false;
  EXPECT_FALSE(significant(failed, options));
}

// A lag is named on its own significance: a row over sqrt 12 is when one command step
// arrived, which the steps do not share. Its sigma still carries it, and a limit is still
// named only past its resolution. (A hex6 actuator lag of 37 ms at 28 Hz rows was fitted at
// 40 +- 10 ms, 7.97 sigma, and not named.)
TEST(QuestionSelection, ALagIsNamedOnItsSignificanceWithTheRowInItsSigma) {
  const QuestionOptions options;
  const double row_s = 1.0 / 28.0;
  RobotModel casters;  // a caster robot's: it has both lags
  casters.drivetrain = DrivetrainKind::kSwpc;
  casters.modules.resize(3);
  const std::vector<Candidate> library =
      candidate_library(casters, Question::kCommandToMotion, MotionPeaks{}, row_s);
  const auto named = [&library](const std::string& name) {
    for (const Candidate& c : library) {
      if (c.name == name) return c;
    }
    ADD_FAILURE() << name << " is not a candidate";
    return Candidate{};
  };
  const Candidate lag = named("actuator_lag");
  ASSERT_EQ(lag.resolution.size(), 1U);
  EXPECT_DOUBLE_EQ(lag.resolution[0], row_s / std::sqrt(12.0));
  EXPECT_FALSE(lag.named_only_when_resolved);
  EXPECT_FALSE(named("steering_lag").named_only_when_resolved);
  EXPECT_TRUE(named("accel_limit").named_only_when_resolved);

  Fitted f = fitted({&lag}, -813.0, 7.97, 1.0);
  f.fit.values = {0.040};
  f.fit.sigmas = {0.010};
  f.fit.covariance = {0.010 * 0.010};
  EXPECT_TRUE(significant(f, options));
  Candidate gated = lag;
  gated.named_only_when_resolved = true;
  Fitted g = f;
  g.effects = {&gated};
  EXPECT_FALSE(significant(g, options)) << "40 +- 14 ms is 2.8 sigma from no lag";
  const std::vector<Fitted> singles = {f};
  const RobotModel base;
  QuestionResult result;
  give_verdict({Question::kCommandToMotion, &base, &singles, singles.data(), &f}, options, result);
  ASSERT_EQ(result.verdict, Verdict::kNamed) << result.summary;
  EXPECT_NEAR(result.named[0].partial_sigmas[0], std::hypot(0.010, lag.resolution[0]), 1e-12);
}

TEST(QuestionSelection, ChoosesTheBestSignificantFullyFittedSingle) {
  const QuestionOptions options;
  const Candidate a = candidate("a");
  const Candidate b = candidate("b");
  const Candidate c = candidate("c");
  const Candidate d = candidate("d");
  const std::vector<Fitted> singles = {
      fitted({&a}, -30.0, 8.0, 2.0),  // significant
      fitted({&b}, -90.0, 8.0, 2.0),  // better, but only screened
      fitted({&c}, -60.0, 3.0, 2.0),  // better, not significant
      fitted({&d}, -40.0, 9.0, 1.0),  // the best significant one
  };
  const std::vector<char> full = {1, 0, 1, 1};
  EXPECT_EQ(choose_single(singles, full, 0.0, options), &singles[3]);
  // None better than the nominal model: nothing chosen.
  EXPECT_EQ(choose_single(singles, full, -100.0, options), nullptr);
  // The best significant one only screened: the next; none fully fitted: nothing chosen.
  EXPECT_EQ(choose_single(singles, {1, 0, 1, 0}, 0.0, options), singles.data());
  EXPECT_EQ(choose_single(singles, {0, 0, 1, 0}, 0.0, options), nullptr);
}

TEST(QuestionSelection, APairReplacesTheSingleOnlyWhenSignificantAndBetter) {
  const QuestionOptions options;
  const Candidate a = candidate("a");
  const Candidate b = candidate("b");
  const Candidate c = candidate("c");
  const Fitted chosen = fitted({&a}, -40.0, 8.0, 2.0);
  std::vector<Fitted> pairs = {
      fitted({&a, &b}, -45.0, 8.0, 2.0),
      fitted({&a, &c}, -70.0, 8.0, 2.0),
  };
  pairs[1].z[1] = 2.0;  // c is not significant beside a
  EXPECT_EQ(choose_pair(pairs, chosen, options), pairs.data());
  pairs[0].fit.bic = -40.0;  // no better than a alone
  EXPECT_EQ(choose_pair(pairs, chosen, options), nullptr);
}

TEST(QuestionSelection, PairsAreTriedBestFirstAndOnlyForAPatternLeft) {
  const Candidate a = candidate("a");
  std::vector<Fitted> singles = {fitted({&a}, -10.0, 8.0, 2.0), fitted({&a}, -30.0, 8.0, 2.0),
                                 fitted({&a}, -50.0, 8.0, 2.0)};
  singles[1].bic_reference = -40.0;  // screened: +10 against its own stretch
  singles[2].fit.ok = false;
  EXPECT_EQ(pair_order(singles), (std::vector<std::size_t>{0, 1, 2}));

  const QuestionOptions options;
  EXPECT_FALSE(pattern_left({misfit("jumps", 20.0, 3.0)}, options));
  EXPECT_FALSE(pattern_left({misfit("heading", 4.0, 3.0), misfit("speed", 20.0, 0.3)}, options));
  EXPECT_TRUE(pattern_left({misfit("jumps", 20.0, 3.0), misfit("heading", 6.0, 0.6)}, options));
}

TEST(QuestionVerdict, AMisfitCountsWhenSignificantAndAsLargeAsTheNoise) {
  const QuestionOptions options;
  const std::vector<MisfitTest> quiet = {misfit("speed", 20.0, 0.9), misfit("heading", 4.0, 3.0)};
  EXPECT_EQ(counting_misfit(quiet, options), nullptr);
  const std::vector<MisfitTest> loud = {misfit("speed", 20.0, 0.9), misfit("heading", 6.0, 1.5),
                                        misfit("accel", 30.0, 5.0)};
  EXPECT_EQ(counting_misfit(loud, options), &loud[1]);
}

TEST(QuestionVerdict, UnexplainedWhenAMisfitCountsWhateverWasSelected) {
  const QuestionOptions options;
  const Candidate a = candidate("a");
  const std::vector<Fitted> singles = {fitted({&a}, -40.0, 8.0, 2.0)};
  const Fitted final = fitted({&a}, -42.0, 8.0, 2.0);
  const RobotModel base;
  QuestionResult result;
  result.misfits = {misfit("heading", 12.0, 2.5)};
  give_verdict({Question::kSensorToPose, &base, &singles, singles.data(), &final}, options, result);
  EXPECT_EQ(result.verdict, Verdict::kUnexplained);
  EXPECT_TRUE(result.named.empty());
  EXPECT_NE(result.summary.find("dx heading pattern (12 sigma, 2.5 noise sigmas)"),
            std::string::npos)
      << result.summary;
  EXPECT_NE(result.summary.find("candidate a (named nothing"), std::string::npos) << result.summary;
}

// The verdict when nothing was selected, with `misfits` left by the nominal model.
QuestionResult verdict_without_selection(const std::vector<Fitted>& singles,
                                         std::vector<MisfitTest> misfits = {}) {
  const QuestionOptions options;
  const Fitted final;
  const RobotModel base;
  QuestionResult result;
  result.misfits = std::move(misfits);
  give_verdict({Question::kSensorToPose, &base, &singles, nullptr, &final}, options, result);
  return result;
}

TEST(QuestionVerdict, NoSignificantGapNamesTheMostSignificantSingle) {
  const Candidate a = candidate("a");
  const Candidate b = candidate("b");
  const std::vector<Fitted> singles = {fitted({&a}, -5.0, 2.5, 0.2), fitted({&b}, -3.0, 3.5, 0.1)};
  const QuestionResult result = verdict_without_selection(singles, {misfit("heading", 3.0, 2.5)});
  EXPECT_EQ(result.verdict, Verdict::kNoSignificantGap);
  EXPECT_NE(result.summary.find("most significant candidate b at 3.5 sigma: below 5 sigma"),
            std::string::npos)
      << result.summary;
}

TEST(QuestionVerdict, NoSignificantGapSaysWhyAStrongCandidateWasNotNamed) {
  // 24 sigma that changes the residual by a tenth of a noise sigma: the summary must not say
  // "below 5".
  const Candidate a = candidate("slip");
  const QuestionResult result = verdict_without_selection({fitted({&a}, -5.0, 24.0, 0.1)});
  EXPECT_EQ(result.verdict, Verdict::kNoSignificantGap);
  EXPECT_NE(result.summary.find("slip at 24 sigma: an RMS change of 0.1 noise sigmas, below 0.5"),
            std::string::npos)
      << result.summary;
}

// A single that takes three quarters of the nominal residual (rss 5 of 20) at 3.8 sigma, which
// would be 8.6 on many windows but rests on 6: what the summary says instead of "the model
// agrees with the run".
Fitted leaning(const Candidate& c, double bic, double z_many) {
  Fitted f = fitted({&c}, bic, 3.8, 1.5);
  f.fit.rss = 5.0;
  f.basis = {SignificanceBasis{6.1, 17.0, z_many}};
  return f;
}

TEST(QuestionVerdict, NothingNamedSaysWhatTheRunLeansTowards) {
  const Candidate lag = candidate("steering_lag");
  const Candidate limit = candidate("accel_limit");
  const std::vector<Fitted> singles = {fitted({&limit}, -20.0, 4.5, 0.8),
                                       leaning(lag, -600.0, 8.6)};
  const QuestionResult result = verdict_without_selection(singles);
  EXPECT_EQ(result.verdict, Verdict::kNoSignificantGap);
  ASSERT_TRUE(result.undecided.has_value());
  EXPECT_EQ(result.undecided->candidate.label(), "steering_lag");
  EXPECT_DOUBLE_EQ(result.undecided->windows, 6.1);
  EXPECT_NEAR(result.undecided->candidate.explained, 0.75, 1e-12);
  for (const char* part :
       {"undecided: the run leans towards steering_lag (steering_lag.k = 1 +- 0.01)",
        "takes 75 % of what the nominal model leaves", "would be 8.6 sigma on many windows",
        "rests on about 6.1", "widened 17 times", "on so few it is 3.8 sigma, below 5"}) {
    EXPECT_NE(result.summary.find(part), std::string::npos) << part << "\n" << result.summary;
  }
  EXPECT_EQ(result.summary.find("agrees with the run"), std::string::npos) << result.summary;
  // Left by a misfit test, the same lean follows what makes the residual unexplained.
  const QuestionResult unexplained =
      verdict_without_selection(singles, {misfit("jumps", 26.0, 43.0)});
  EXPECT_EQ(unexplained.verdict, Verdict::kUnexplained);
  EXPECT_NE(unexplained.summary.find("candidate none. Undecided: the run leans towards "
                                     "steering_lag"),
            std::string::npos)
      << unexplained.summary;
}

// Where a lean takes the gap: four windows (starting at 0, 1, 2, 3 s) of two channels; the
// nominal model leaves 3, 0, 2, 4 (whitened) in the first channel and 1 everywhere in the
// second, the candidate 1, 0, 0, 4 and 1, 1, 0, 1. Its gains per window: 8, -1, 5, 0, of which
// the two positive carry all.
TEST(QuestionVerdict, ALeanSaysInWhichWindowsItTakesTheGap) {
  const Candidate lag = candidate("steering_lag");
  std::vector<Fitted> singles = {leaning(lag, -600.0, 8.6)};
  singles[0].fit.residuals = {1.0, 0.0, 0.0, 4.0, 1.0, 1.0, 0.0, 1.0};
  FitOutcome nominal;
  nominal.ok = true;
  nominal.residuals = {3.0, 0.0, 2.0, 4.0, 1.0, 0.0, 1.0, 1.0};
  const std::vector<double> start_s = {0.0, 1.0, 2.0, 3.0};
  const QuestionOptions options;
  const Fitted final;
  const RobotModel base;
  QuestionResult result;
  give_verdict({Question::kCommandToMotion, &base, &singles, nullptr, &final, nullptr, 0.0,
                &nominal, &start_s},
               options, result);
  ASSERT_TRUE(result.undecided.has_value());
  EXPECT_EQ(result.undecided->where_s, (std::vector<double>{0.0, 2.0}));
  EXPECT_DOUBLE_EQ(result.undecided->where_share, 1.0);
  EXPECT_NE(result.summary.find("100 % of it in the windows from 0.0, 2.0 s"), std::string::npos)
      << result.summary;
}

// A lag of 0.057 +- 0.012 s where the replay resolves 0.0103 s: 3.7 sigma from nothing with
// the sigma its few windows leave, 5.4 with the sigma many would (0.012 / sqrt(17)); within
// 2 resolutions of nothing, not resolved on any number of windows.
TEST(QuestionVerdict, ALeanIsJudgedAgainstTheResolutionAsOnManyWindows) {
  const Candidate lag = candidate("steering_lag", 0.0103);
  Fitted resolved = leaning(lag, -600.0, 8.6);
  resolved.fit.values = {0.057};
  resolved.fit.sigmas = {0.012};
  EXPECT_TRUE(verdict_without_selection({resolved}).undecided.has_value());
  Fitted unresolved = resolved;
  unresolved.fit.values = {0.02};
  EXPECT_FALSE(verdict_without_selection({unresolved}).undecided.has_value());
}

TEST(QuestionVerdict, NoLeanWithoutMostOfTheGapOnFewWindowsFromTheBestCandidate) {
  const Candidate lag = candidate("steering_lag");
  const Candidate other = candidate("actuator_lag");
  // Half the gap, not more (the fixture's rss 10 of 20).
  Fitted half = leaning(lag, -600.0, 8.6);
  half.fit.rss = 10.0;
  // As significant on many windows as on few: not the windows' doing.
  const Fitted weak = leaning(lag, -600.0, 4.0);
  // Large on few windows but changing the residual by a tenth of a noise sigma.
  Fitted small = leaning(lag, -600.0, 8.6);
  small.size = {0.1};
  // Not the best by BIC: the best takes no lean.
  const std::vector<Fitted> second = {fitted({&other}, -700.0, 4.0, 0.8),
                                      leaning(lag, -600.0, 8.6)};
  for (const std::vector<Fitted>& singles :
       {std::vector<Fitted>{half}, std::vector<Fitted>{weak}, std::vector<Fitted>{small}, second}) {
    const QuestionResult result = verdict_without_selection(singles);
    EXPECT_EQ(result.verdict, Verdict::kNoSignificantGap);
    EXPECT_FALSE(result.undecided.has_value()) << result.summary;
    EXPECT_NE(result.summary.find("agrees with the run to within its noise"), std::string::npos)
        << result.summary;
  }
}

TEST(QuestionVerdict, NamedCarriesTheRefittedValuesIntoTheModel) {
  const QuestionOptions options;
  Candidate bias = candidate("gyro_bias", 0.003);
  bias.keys = {"bias_rad_s"};
  const std::vector<Fitted> singles = {fitted({&bias}, -40.0, 8.0, 2.0)};
  Fitted final = fitted({&bias}, -41.0, 7.5, 1.8);
  final.fit.values = {0.02};
  final.fit.sigmas = {0.004};
  final.fit.covariance = {0.004 * 0.004};
  const RobotModel base;
  QuestionResult result;
  give_verdict({Question::kSensorToPose, &base, &singles, singles.data(), &final}, options, result);
  ASSERT_EQ(result.verdict, Verdict::kNamed);
  ASSERT_EQ(result.named.size(), 1U);
  const FittedEffect& fe = result.named[0];
  EXPECT_EQ(fe.name, "gyro_bias");
  EXPECT_DOUBLE_EQ(fe.z, 7.5);
  EXPECT_DOUBLE_EQ(fe.values[0], 0.02);
  EXPECT_DOUBLE_EQ(fe.sigmas[0], 0.005);  // statistical and resolution in quadrature
  EXPECT_DOUBLE_EQ(fe.partial_sigmas[0], 0.005);
  EXPECT_EQ(fe.observable_combinations, 1U);
  EXPECT_DOUBLE_EQ(result.augmented.effects.at("gyro_bias").at("bias_rad_s"), 0.02);
  EXPECT_EQ(result.summary.rfind("Named gyro_bias (", 0), 0U) << result.summary;
  EXPECT_NE(result.summary.find("significant at 7.5 sigma, an RMS change of 1.8 noise sigmas"),
            std::string::npos)
      << result.summary;
}

// A named effect is reported with the significant singles whose BIC lies within kRivalBic of
// its own (the run barely tells them apart), best first; not with one further off, one that
// is not significant, or one not fitted on every window.
TEST(QuestionVerdict, ANamedEffectComesWithTheRivalsTheRunBarelyTellsItFrom) {
  const QuestionOptions options;
  Candidate radius = candidate("wheel_radius");
  Candidate offset = candidate("steering_offset");
  Candidate scale = candidate("gyro_scale");
  Candidate bias = candidate("gyro_bias");
  Candidate slip = candidate("slip");
  const std::vector<Fitted> singles = {
      fitted({&radius}, -70.0, 8.8, 0.9),  // chosen
      fitted({&offset}, -67.9, 8.7, 0.9),  // 2.1 apart: a rival
      fitted({&scale}, -63.0, 9.0, 0.9),   // 7 apart: told apart
      fitted({&bias}, -69.0, 3.0, 0.9),    // not significant on its own
      fitted({&slip}, -69.5, 8.0, 0.9)};   // screened: not fitted on every window
  const std::vector<char> full = {1, 1, 1, 1, 0};
  const Fitted final = fitted({&radius}, -70.0, 8.8, 0.9);
  const RobotModel base;
  QuestionResult result;
  give_verdict({Question::kSensorToPose, &base, &singles, singles.data(), &final, &full, 0.0},
               options, result);
  ASSERT_EQ(result.verdict, Verdict::kNamed);
  ASSERT_EQ(result.rivals.size(), 1U);
  EXPECT_EQ(result.rivals[0].effects, std::vector<std::string>{"steering_offset"});
  EXPECT_NE(result.summary.find("The run barely tells it from steering_offset (BIC 2.1 higher, "
                                "itself significant at 8.7 sigma)"),
            std::string::npos)
      << result.summary;

  // Told apart from everything: no rival, no sentence.
  const std::vector<Fitted> alone = {fitted({&radius}, -70.0, 8.8, 0.9),
                                     fitted({&scale}, -63.0, 9.0, 0.9)};
  QuestionResult clear;
  give_verdict({Question::kSensorToPose, &base, &alone, alone.data(), &final}, options, clear);
  EXPECT_TRUE(clear.rivals.empty());
  EXPECT_EQ(clear.summary.find("barely tells"), std::string::npos) << clear.summary;
}

// A gap the misfit tests detected is put down to the best candidate by BIC alone: at
// min_z_attribute, large enough, resolved, and with fewer parameters than the jumps it takes
// away; never to a worse one when the best falls short.
TEST(QuestionSelection, AGapIsPutDownToTheBestCandidateOnly) {
  const QuestionOptions options;
  const Candidate a = candidate("a");
  const Candidate b = candidate("b");
  const Candidate blurred = candidate("blurred", 0.5);  // resolves 1.0 at 2 sigma: too little
  std::vector<Fitted> singles = {fitted({&a}, -30.0, 8.0, 2.0), fitted({&b}, -60.0, 4.2, 2.0)};
  const std::vector<char> full = {1, 1};
  const MisfitTest gap = misfit("trend", 9.0, 2.0);
  EXPECT_EQ(choose_attribution(singles, full, 0.0, gap, options), &singles[1]);
  singles[1].z[0] = 2.9;  // the best below min_z_attribute: not the significant one either
  EXPECT_EQ(choose_attribution(singles, full, 0.0, gap, options), nullptr);
  singles[1].z[0] = 4.2;
  singles[1].size[0] = 0.3;  // too small to matter
  EXPECT_EQ(choose_attribution(singles, full, 0.0, gap, options), nullptr);
  singles[1].size[0] = 2.0;
  EXPECT_EQ(choose_attribution(singles, {1, 0}, 0.0, gap, options), singles.data())
      << "screened only";
  EXPECT_EQ(choose_attribution(singles, full, -100.0, gap, options), nullptr)
      << "none beats nominal";
  const std::vector<Fitted> unresolved = {fitted({&blurred}, -60.0, 4.2, 2.0)};
  EXPECT_EQ(choose_attribution(unresolved, {1}, 0.0, gap, options), nullptr);
  QuestionOptions strict = options;
  strict.min_z_attribute = 5.0;
  EXPECT_EQ(choose_attribution({fitted({&b}, -60.0, 4.2, 2.0)}, {1}, 0.0, gap, strict), nullptr);
  // A gap of jumps: only a candidate with fewer parameters than jumps names it.
  MisfitTest jumps = misfit("jumps", 12.0, 20.0);
  jumps.jumps = {{3, 1}, {9, 1}};
  EXPECT_EQ(choose_attribution(singles, full, 0.0, jumps, options), &singles[1]);
  Candidate offsets = candidate("steering_offset");
  offsets.params.push_back(offsets.params[0]);
  offsets.keys = {"module_1_rad", "module_2_rad"};
  offsets.identity = {0.0, 0.0};
  offsets.inverse = {0, 0};
  offsets.resolution = {0.0, 0.0};
  offsets.relative_resolution = {0.0, 0.0};
  std::vector<Fitted> two = {fitted({&offsets}, -60.0, 4.2, 2.0)};
  two[0].fit.values = {1.0, 1.0};
  two[0].fit.sigmas = {0.01, 0.01};
  EXPECT_EQ(choose_attribution(two, {1}, 0.0, jumps, options), nullptr);
  jumps.jumps.push_back({20, 2});
  EXPECT_EQ(choose_attribution(two, {1}, 0.0, jumps, options), two.data());
}

TEST(QuestionVerdict, AnAttributedGapIsNamedWithTheTestThatFoundIt) {
  const QuestionOptions options;
  const Candidate lag = candidate("steering_lag");
  const std::vector<Fitted> singles = {fitted({&lag}, -1000.0, 4.96, 6.2)};
  const Fitted final = fitted({&lag}, -1001.0, 4.96, 6.2);
  const RobotModel base;
  QuestionResult result;
  result.misfits = {misfit("speed", 1.0, 0.2)};
  result.attributed_gap = {misfit("jumps", 11.0, 4.0)};
  give_verdict({Question::kCommandToMotion, &base, &singles, singles.data(), &final}, options,
               result);
  ASSERT_EQ(result.verdict, Verdict::kNamed);
  ASSERT_EQ(result.named.size(), 1U);
  EXPECT_NE(result.summary.find("the gap the misfit tests found without it (dx jumps pattern, 11 "
                                "sigma) is gone with it, the best candidate at 4.96 sigma"),
            std::string::npos)
      << result.summary;
}

// Jumps that a selected effect leaves of a change at least twice their size where it acts are
// its approximate form: they do not make the residual unexplained. One the effect did not
// bring down (or made) still does.
TEST(QuestionVerdict, JumpsLeftOfALargerChangeAreTheEffectsForm) {
  QuestionReplay replay;
  replay.windows = 4;
  ChannelInfo dx;
  dx.name = "dx";
  ChannelInfo dy;
  dy.name = "dy";
  replay.channels = {dx, dy};
  // dx: window 1 went from 30 to 8 (a change of -22: 8 is within half of it); window 2+3, a
  // span, from 12 + 12 to 3 + 2. dy: window 0 from 2 to -8 (the effect made it).
  const std::vector<double> before = {0.0, 30.0, 12.0, 12.0, 2.0, 0.0, 0.0, 0.0};
  const std::vector<double> after = {0.0, 8.0, 3.0, 2.0, -8.0, 0.0, 0.0, 0.0};
  MisfitTest x = misfit("jumps", 9.0, 12.0);
  x.channel = "dx";
  x.jumps = {{1, 1}, {2, 2}};
  MisfitTest y = misfit("jumps", 7.0, 10.0);
  y.channel = "dy";
  y.jumps = {{0, 1}};
  std::vector<MisfitTest> misfits = {x, y, misfit("trend", 6.0, 2.0)};
  mark_remnant_jumps(replay, before, after, misfits);
  EXPECT_TRUE(misfits[0].remnant);
  EXPECT_FALSE(misfits[1].remnant);
  EXPECT_FALSE(misfits[2].remnant);
  const QuestionOptions options;
  EXPECT_EQ(counting_misfit(misfits, options), &misfits[1]);
  // Window 1 left at 12 of a change of 18: more than half of it, not a remnant.
  std::vector<double> worse = after;
  worse[1] = 12.0;
  std::vector<MisfitTest> again = {x};
  mark_remnant_jumps(replay, before, worse, again);
  EXPECT_FALSE(again[0].remnant);
  EXPECT_EQ(counting_misfit(again, options), again.data());
}

// Two steering offsets whose sum the run leaves open beside a nuisance (the motion capture's
// yaw offset): a combination not fixed over all three. The effects' part keeps that open
// direction; one that is nearly all nuisance leaves the effects fixed.
TEST(QuestionFitStages, TheEffectsPartKeepsWhatANuisanceLeavesOpen) {
  FitOutcome joint;
  joint.ok = true;
  joint.values = {0.01, -0.02, 0.03};
  joint.sigmas = {kInf, kInf, kInf};
  joint.naive_sigmas = joint.sigmas;
  joint.observable = {0, 0, 0};
  joint.scales = {0.01, 0.01, 0.02};
  joint.covariance.assign(9, 0.0);
  joint.naive_covariance.assign(9, 0.0);
  const double third = 1.0 / std::sqrt(3.0);
  joint.unfixed = {{third, third, -third}, {0.05, 0.0, std::sqrt(1.0 - 0.05 * 0.05)}};
  const FitOutcome part = effects_part(joint, 2);
  ASSERT_EQ(part.unfixed.size(), 1U) << "the second is 0.25 % effect: a nuisance's own";
  EXPECT_DOUBLE_EQ(part.unfixed[0][0], third);
  EXPECT_DOUBLE_EQ(part.unfixed[0][1], third);
  EXPECT_EQ(part.scales, (std::vector<double>{0.01, 0.01}));
}

// The effect's covariance from such a fit (full rank in the effects' block, as the nuisance's
// part is cut off) loses the open sum: what the run fixes is the difference alone, and a
// value off along the sum is not judged against a sigma the fit never had.
TEST(QuestionVerdict, ACombinationLeftOpenIsNotCountedAsObservable) {
  Candidate offsets = candidate("steering_offset");
  offsets.keys = {"module_1_rad", "module_2_rad"};
  offsets.params.push_back(offsets.params[0]);
  offsets.identity = {0.0, 0.0};
  offsets.inverse = {0, 0};
  offsets.resolution = {0.0, 0.0};
  offsets.relative_resolution = {0.0, 0.0};
  Fitted final = fitted({&offsets}, -41.0, 7.5, 1.8);
  final.fit.values = {0.01, -0.02};
  final.fit.sigmas = {kInf, kInf};
  // Variance 4e-6 along the sum (what the cut-off nuisance leaves), 1e-6 along the difference.
  final.fit.covariance = {2.5e-6, 1.5e-6, 1.5e-6, 2.5e-6};
  final.fit.scales = {0.01, 0.01};
  const double half = std::sqrt(0.5);
  final.fit.unfixed = {{half, half}};
  const FittedEffect open = fitted_effect(final, score_of(final), 0, 0);
  EXPECT_EQ(open.observable_combinations, 1U);
  // What is left is the difference's variance, half of it on each offset.
  EXPECT_NEAR(open.partial_sigmas[0], std::sqrt(0.5e-6), 1e-12);
  std::size_t rank = 0;
  EXPECT_NEAR(mahalanobis_squared({0.001, 0.001}, open.fit_covariance, rank), 0.0, 1e-9);
  EXPECT_NEAR(mahalanobis_squared({0.001, -0.001}, open.fit_covariance, rank), 2.0, 1e-6);

  final.fit.unfixed.clear();
  const FittedEffect fixed = fitted_effect(final, score_of(final), 0, 0);
  EXPECT_EQ(fixed.observable_combinations, 2U);
  EXPECT_NEAR(mahalanobis_squared({0.001, 0.001}, fixed.fit_covariance, rank), 0.5, 1e-6);
}

// In a pair, a combination left open that is nearly all the second effect (a trace, 0.25 %
// of its squared length, in the first) leaves the first one fixed, and the second open.
TEST(QuestionVerdict, AnOpenCombinationIsJudgedPerEffectOfAPair) {
  const Candidate a = candidate("a");
  const Candidate b = candidate("b");
  Fitted final = fitted({&a, &b}, -41.0, 7.5, 1.8);
  final.fit.covariance = {1e-4, 0.0, 0.0, 1e-4};
  final.fit.scales = {1.0, 1.0};
  final.fit.unfixed = {{0.05, std::sqrt(1.0 - 0.05 * 0.05)}};
  const CandidateScore s = score_of(final);
  const FittedEffect first = fitted_effect(final, s, 0, 0);
  const FittedEffect second = fitted_effect(final, s, 1, 1);
  EXPECT_EQ(first.observable_combinations, 1U);
  EXPECT_NEAR(first.partial_sigmas[0], 0.01, 1e-12);
  EXPECT_EQ(second.observable_combinations, 0U);
  // 0.12 in the first effect (1.44 %, past the 1 % line): open in both.
  final.fit.unfixed = {{0.12, std::sqrt(1.0 - 0.12 * 0.12)}};
  EXPECT_EQ(fitted_effect(final, s, 0, 0).observable_combinations, 0U);
}

// A second effect is looked for when another single is significant on its own, even with no
// pattern left (a gyro bias and a wheel-radius difference both turn the heading).
TEST(QuestionSelection, AnotherSignificantSingleCallsForAPair) {
  const QuestionOptions options;
  const Candidate a = candidate("a");
  const Candidate b = candidate("b");
  std::vector<Fitted> singles = {fitted({&a}, -50.0, 9.0, 1.0), fitted({&b}, -20.0, 4.9, 1.0)};
  EXPECT_FALSE(another_significant(singles, singles.data(), options));
  singles[1] = fitted({&b}, -20.0, 5.8, 1.0);
  EXPECT_TRUE(another_significant(singles, singles.data(), options));
  EXPECT_TRUE(another_significant(singles, std::next(singles.data()), options));
  singles[1].fit.ok = false;
  EXPECT_FALSE(another_significant(singles, singles.data(), options));
}

// The noise the fit took, against what the model's sensor figures state: a channel at or
// above the ratio is reported, largest first, with the figures it was judged against.
TEST(QuestionNoise, NoiseBeyondTheStatedFiguresIsReported) {
  QuestionReplay replay;
  replay.channels = {{"dx", "m"}, {"dyaw", "rad"}, {"dyaw_gyro", "rad"}};
  replay.stated_variance = {1e-8, 1e-6, 0.0};  // the third states nothing
  replay.stated_source = {"position 1e-4", "yaw 1e-3", ""};
  NoiseModel noise;
  noise.a = {1.5e-8, 2.5e-5, 1.0};  // 1.22x, 5x, unstated
  noise.b = {1.0, 1.0, 1.0};        // what grows with motion is not judged here
  const std::vector<NoiseFinding> findings = stated_noise_findings(replay, noise, 2.0);
  ASSERT_EQ(findings.size(), 1U);
  EXPECT_EQ(findings[0].channel.name, "dyaw");
  EXPECT_NEAR(findings[0].ratio, 5.0, 1e-12);
  EXPECT_NEAR(findings[0].measured_sigma, 5e-3, 1e-12);
  EXPECT_NEAR(findings[0].stated_sigma, 1e-3, 1e-12);
  EXPECT_EQ(findings[0].source, "yaw 1e-3");

  noise.a[0] = 9e-8;  // 3x: now two, the larger first
  const std::vector<NoiseFinding> two = stated_noise_findings(replay, noise, 2.0);
  ASSERT_EQ(two.size(), 2U);
  EXPECT_EQ(two[0].channel.name, "dyaw");
  EXPECT_EQ(two[1].channel.name, "dx");
  EXPECT_TRUE(stated_noise_findings(replay, noise, 6.0).empty());
}

// The calibration stage on a differential robot with nothing named: slip (no parameter of the
// robot model) has the best BIC, track_width is below the naming significance and changes a
// window by a third of the noise, gyro_bias is below the calibration's.
struct CalibrationCase {
  Candidate slip = candidate("slip");
  Candidate track = candidate("track_width");
  Candidate bias = candidate("gyro_bias");
  std::vector<Fitted> singles = {fitted({&slip}, -20.0, 4.5, 0.1),
                                 fitted({&track}, -7.0, 3.6, 0.35),
                                 fitted({&bias}, -9.0, 2.5, 0.8)};
  std::vector<char> full = {1, 1, 1};
  RobotModel base;
  Fitted final;

  QuestionResult decide(bool calibrate, std::vector<MisfitTest> misfits = {}) {
    track.keys = {"scale"};
    singles[1].fit.values = {1.011};
    QuestionOptions options;
    options.calibrate = calibrate;
    QuestionResult result;
    result.augmented = base;
    result.misfits = std::move(misfits);
    const VerdictInputs in{Question::kSensorToPose, &base, &singles, nullptr, &final, &full, 0.0};
    give_verdict(in, options, result);
    calibrate_own_parameters(in, options, result);
    return result;
  }
};

TEST(QuestionCalibration, ARobotParameterTooSmallToNameIsCalibratedWhenSignificant) {
  CalibrationCase c;
  const QuestionResult result = c.decide(true);
  EXPECT_EQ(result.verdict, Verdict::kNoSignificantGap);
  ASSERT_EQ(result.calibrated.size(), 1U);
  EXPECT_EQ(result.calibrated[0].name, "track_width");
  EXPECT_TRUE(result.named.empty());
  EXPECT_DOUBLE_EQ(result.augmented.effects.at("track_width").at("scale"), 1.011);
  EXPECT_EQ(result.augmented.effects.count("slip"), 0U);
  EXPECT_NE(result.summary.find("Calibrated track_width: significant at 3.6 sigma"),
            std::string::npos)
      << result.summary;
}

TEST(QuestionCalibration, NothingIsCalibratedUnlessAskedFittedWholeAndExplained) {
  {
    CalibrationCase c;
    const QuestionResult result = c.decide(false);
    EXPECT_TRUE(result.calibrated.empty());
    EXPECT_TRUE(result.augmented.effects.empty());
  }
  {
    CalibrationCase c;  // the track fitted on the screening stretch only
    c.full = {1, 0, 1};
    EXPECT_TRUE(c.decide(true).calibrated.empty());
  }
  {
    CalibrationCase c;  // worse than the nominal model
    c.singles[1].fit.bic = 1.0;
    EXPECT_TRUE(c.decide(true).calibrated.empty());
  }
  {
    CalibrationCase c;  // a residual the library cannot explain: no value is trusted
    const QuestionResult result = c.decide(true, {misfit("heading", 12.0, 2.5)});
    EXPECT_EQ(result.verdict, Verdict::kUnexplained);
    EXPECT_TRUE(result.calibrated.empty());
  }
  {
    CalibrationCase c;  // on an SWPC robot a track width is no parameter of the model
    c.base.drivetrain = DrivetrainKind::kSwpc;
    EXPECT_TRUE(c.decide(true).calibrated.empty());
  }
}

}  // namespace
}  // namespace swivel::model_gap::detail
