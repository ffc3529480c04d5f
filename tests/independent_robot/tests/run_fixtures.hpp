// SPDX-License-Identifier: Apache-2.0
#pragma once
// Quiet runs, step tours and row lookups shared by the generator's tests.

#include <vector>

#include "swivel/independent/run_spec.hpp"
#include "swivel/independent/simulation.hpp"

namespace swivel::independent::test {

/// One encoder count, rad.
double count_rad();

/// A spec with every random part off, the robot starting at the origin facing +x.
RunSpec quiet_run(Robot robot, double duration_s, std::vector<TourSegment> tour);

/// A tour that stands still until `start_s`, then steps to `target` and holds it.
std::vector<TourSegment> step_tour(double start_s, const Twist& target);

/// Rows with `from_s <= t < to_s`.
std::vector<const RunRow*> rows_between(const RunRecord& record, double from_s, double to_s);

/// The first row at or after `t_s`.
const RunRow& row_at(const RunRecord& record, double t_s);

/// Linear interpolation of wheel `i`'s encoder angle at `t_s`.
double wheel_at(const RunRecord& record, std::size_t i, double t_s);

/// The angle in (-pi, pi].
double wrapped(double a);

}  // namespace swivel::independent::test
