// SPDX-License-Identifier: Apache-2.0
#pragma once
// What kind of motion a differential run holds, for the candidates its geometry can tell apart:
// a run that turns in one way only cannot tell a turn-dependent track from a track width, and
// one that drives one circle cannot tell wheel radii from the tracked body's lever arm.
// Internal to the workflow; tested through this header.

#include <cstddef>
#include <utility>
#include <vector>

#include "swivel/model_gap/run_data.hpp"

namespace swivel::model_gap {

/// Below this spread of spin shares a run moves in one way only (see spin_share_spread).
inline constexpr double kMinSpinShareSpread = 0.3;

/// Below this share of its turning on arcs that bend the other way a run drives one circle.
inline constexpr double kMinOtherWayShare = 0.1;

/// A differential run's wheel travel (left, right, in radians) over stretches of at least
/// `stretch_s` (0: row by row); empty for an SWPC run.
std::vector<std::pair<double, double>> wheel_steps(const RunData& run, double stretch_s);

/// How much the run's turning differs in kind (the 10th to 90th percentile of the spin share,
/// rows weighted by how far they turned).
double turn_kind_spread(const RunData& run);

/// Whether wheel travel over stretches of about a second (wheel_steps(run, 1.0)) drives one
/// circle: one kind of motion, bending one way, that turns.
bool drives_one_circle(const std::vector<std::pair<double, double>>& seconds);

}  // namespace swivel::model_gap
