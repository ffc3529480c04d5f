// SPDX-License-Identifier: Apache-2.0
#pragma once
// The validation runs of swivel-bench-model-gap: drawn from seed ranges that were never used
// while the model-gap workflow or this generator was developed (tools/lab/GAP.md
// "Validation on runs made another way"). Each case is a function of its seed alone. The
// smoke range serves `--quick` and the tests, so that a look at a smoke run never sees a
// validation run.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "swivel/second/second_robot.hpp"

namespace swivel::second {

enum class CaseKind {
  kClean,    ///< the true robot is what its model states (motion capture mounted anyhow)
  kLibrary,  ///< one effect of the workflow's library
  kOutside,  ///< a slippery floor: the contacts saturate, which the library has no name for
};
const char* case_kind_name(CaseKind kind);

struct ValidationCase {
  std::string id;  ///< e.g. "clean/7340001"
  CaseKind kind = CaseKind::kClean;
  std::string description;  ///< robot, rate, script, what is hidden
  RunSpec spec;
  std::vector<ExpectedEffect> expected;  ///< library effects a correct workflow names
};

/// The first seed of each kind of case in one set of runs (case i has first + i).
struct SeedRanges {
  std::uint64_t clean = 0;
  std::uint64_t library = 0;
  std::uint64_t outside = 0;
};

// The validation set: seeds drawn at random on 2026-11-29 (the fifteenth draw) and never
// used while developing.
inline constexpr SeedRanges kValidationSeeds{61136331, 77438982, 97741474};
// The first validation set (2026-11-26). It was measured again after each of several changes
// of the workflow on 2026-11-27, so it is development data now: reported, never judged.
inline constexpr SeedRanges kFirstValidationSeeds{7340001, 7350001, 7360001};
// The second validation set (drawn on 2026-11-27), looked at three times that day after
// changes found on other runs: development data now, like the first.
inline constexpr SeedRanges kSecondValidationSeeds{28880001, 28890001, 28900001};
// The third (drawn on 2026-11-27): measured once, then one of its runs showed a fault of the
// fit that was fixed: development data now.
inline constexpr SeedRanges kThirdValidationSeeds{72548103, 11811626, 78109134};
// The fourth (drawn on 2026-11-27): measured three times, no change found on it; seeds were
// drawn again for the next change of the workflow (the sandwich's lagged scores), so it is
// development data now.
inline constexpr SeedRanges kFourthValidationSeeds{26341837, 57381725, 59075466};
// The fifth (drawn on 2026-11-27): measured once after the sandwich's lagged scores; seeds
// were drawn again for the next change (casters scrubbing while steering late).
inline constexpr SeedRanges kFifthValidationSeeds{98462895, 59651338, 63658172};
// The sixth (drawn on 2026-11-27): measured after the scrubbing casters, and again after a
// fix of that rule found on a padded run (the same figures); seeds were drawn again for the
// next change (combinations a nuisance leaves open).
inline constexpr SeedRanges kSixthValidationSeeds{76076734, 16041776, 65394149};
// The seventh (drawn on 2026-11-28): measured once after combinations a nuisance leaves open;
// seeds were drawn again for the next change (a detected gap put down to the candidate that
// takes it away, and jumps left where a named effect acts).
inline constexpr SeedRanges kSeventhValidationSeeds{96537188, 69718967, 14479882};
// The eighth (drawn on 2026-11-28): measured once after a detected gap put down to the
// candidate that takes it away; seeds were drawn again for the next changes (a gap of jumps
// only to fewer parameters than jumps, casters steering late scrubbing at twice the median).
inline constexpr SeedRanges kEighthValidationSeeds{50642445, 11965200, 28125553};
// The ninth (drawn on 2026-11-28, the eighth draw): measured once after its two changes, and
// again with friction-limited geometry counted apart (a report, not a rule); seeds were drawn
// again for the next change (where between rows a sampled gyro's rate belongs).
inline constexpr SeedRanges kNinthValidationSeeds{19798844, 48952844, 39403243};
// The tenth (drawn on 2026-11-28, the ninth draw): measured once after where between rows a
// sampled gyro's rate belongs; seeds were drawn again for the next changes (the command
// replay's limiter through each command's span, an effect sized beside the nuisance it was
// fitted at).
inline constexpr SeedRanges kTenthValidationSeeds{42696577, 13114082, 59591776};
// The eleventh (drawn on 2026-11-28, the tenth draw): measured once after the command replay's
// two changes; seeds were drawn again for the next change (the jumps test's transients split
// across a noisy and a quiet window).
inline constexpr SeedRanges kEleventhValidationSeeds{90474719, 72502256, 88754006};
// The twelfth (drawn on 2026-11-28, the eleventh draw): measured once after the jumps test's
// split transients, and again with the caster runs split by whether their servos fight their
// tyres (a report, not a rule); seeds were drawn again for the next change (caster robots'
// servos yielding to their tyres in the command replay).
inline constexpr SeedRanges kTwelfthValidationSeeds{48877460, 33651945, 32770834};
// The thirteenth (drawn on 2026-11-29, the twelfth draw): measured once after the servos'
// yield in the command replay; nine of its missed caster runs were then replayed while a
// second start for the yield was tried (not kept), so seeds were drawn again.
inline constexpr SeedRanges kThirteenthValidationSeeds{77376489, 90621190, 83477096};
// The fourteenth (drawn on 2026-11-29, the thirteenth draw): measured once with the
// workflow the twelfth draw had judged; its missed runs were then replayed while a
// force-balanced dead reckoning (not kept) and the sensor question's anchors were tried, so
// seeds were drawn again.
inline constexpr SeedRanges kFourteenthValidationSeeds{15340781, 15071500, 27908692};
// The fifteenth (drawn on 2026-11-29, the fourteenth draw): measured once after the sensor
// question's window ends came to follow each replay's path; its missed caster drives were
// then replayed to see why, and a lag stopped being held back by its row resolution, so
// seeds were drawn again.
inline constexpr SeedRanges kFifteenthValidationSeeds{33893527, 43069030, 81204875};
// Smoke seeds (tests, --quick): a range of their own, so that looking at them reveals nothing
// of the validation runs.
inline constexpr SeedRanges kSmokeSeeds{5001, 6001, 6501};

inline constexpr std::size_t kValidationCleanRuns = 240;
inline constexpr std::size_t kValidationLibraryRuns = 68;  ///< 4 of each robot-effect pair
inline constexpr std::size_t kValidationOutsideRuns = 12;

inline constexpr double kValidationDurationS = 80.0;

/// The seed ranges a set is named by on the command lines (seed_set_names()); nullptr for
/// another name.
const SeedRanges* seed_ranges_named(std::string_view name);
/// Those names: `smoke`, `validation`, then the earlier validation sets (development data
/// now), `first-validation` to `fifteenth-validation`.
const std::vector<std::string>& seed_set_names();

/// One case of each kind, from its seed (and its index within the range, which spreads the
/// cases evenly over robots and effects).
ValidationCase clean_case(std::uint64_t first_seed, std::size_t index);
ValidationCase library_case(std::uint64_t first_seed, std::size_t index);
ValidationCase outside_case(std::uint64_t first_seed, std::size_t index);

/// The effects library_case cycles through, as "robot kind/effect" pairs (17).
std::vector<std::string> library_case_effects();

/// `clean`, `library` and `outside` cases from the seed ranges `seeds`.
std::vector<ValidationCase> validation_set(const SeedRanges& seeds, std::size_t clean,
                                           std::size_t library, std::size_t outside);

}  // namespace swivel::second
