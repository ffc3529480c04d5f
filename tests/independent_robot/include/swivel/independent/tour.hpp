// SPDX-License-Identifier: Apache-2.0
#pragma once
// Tours: the user's body-twist setpoint as a function of time. The standard tour of each
// robot is drawn from the run's seed so that every library effect shows: it stands still
// first, then mixes straight runs, arcs, turns in place, stops and speed changes (swpc4 also
// sideways, diagonal and translating while rotating), with steps that exceed the robot's
// acceleration limits and ramps that stay below them, and more turns to the left than to the
// right so that several radians of net rotation accumulate.

#include <cstdint>
#include <vector>

#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

/// How long every standard tour stands still before it first moves, at least.
inline constexpr double kTourStandStillS = 1.5;

/// The setpoint of `tour` at time `t_s` (zero before the first segment).
Twist setpoint_at(const std::vector<TourSegment>& tour, double t_s);

/// The standard tour of `robot` for `seed`, `duration_s` long, ending at rest.
std::vector<TourSegment> make_tour(Robot robot, Steering steering, std::uint64_t seed,
                                   double duration_s);

/// Checks a hand-made tour: starts increasing from 0, ramps within their segment, finite
/// targets, and no sideways setpoint for the docent.
/// @throws std::invalid_argument naming the segment and the problem.
void validate_tour(Robot robot, const std::vector<TourSegment>& tour);

}  // namespace swivel::independent
