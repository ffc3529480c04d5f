// SPDX-License-Identifier: Apache-2.0
#include "motion_kind.hpp"

#include <algorithm>
#include <cmath>

#include "swivel/sim/effects.hpp"

namespace swivel::model_gap {
namespace {

// The spread (10th to 90th percentile) of the spin share (sim::spin_share) of wheel steps,
// each weighted by what `weight(left, right)` gives it.
template <typename Weight>
double spin_share_spread(const std::vector<std::pair<double, double>>& steps, Weight weight) {
  std::vector<std::pair<double, double>> shares;  // (share, weight)
  double total = 0.0;
  for (const auto& [l, r] : steps) {
    const double w = weight(l, r);
    if (w <= 0.0) continue;
    shares.emplace_back(sim::spin_share(l, r), w);
    total += w;
  }
  if (shares.empty()) return 0.0;
  std::sort(shares.begin(), shares.end());
  const auto quantile = [&](double q) {
    double acc = 0.0;
    for (const auto& [share, w] : shares) {
      acc += w;
      if (acc >= q * total) return share;
    }
    return shares.back().first;
  };
  return quantile(0.9) - quantile(0.1);
}

// How much the run's motion differs in kind, seconds weighted by how far the wheels rolled
// (row by row, a slow wheel's counts come in bursts). Below kMinSpinShareSpread the run drives
// one arc only, or straight only.
double motion_kind_spread(const std::vector<std::pair<double, double>>& seconds) {
  return spin_share_spread(seconds, [](double l, double r) { return std::abs(l) + std::abs(r); });
}

}  // namespace

// A differential run's wheel travel (left, right, in radians) over stretches of at least
// `stretch_s` (0: row by row).
std::vector<std::pair<double, double>> wheel_steps(const RunData& run, double stretch_s) {
  std::vector<std::pair<double, double>> steps;
  if (run.drivetrain != DrivetrainKind::kDifferential) return steps;
  std::size_t from = 0;
  for (std::size_t k = 1; k < run.size(); ++k) {
    if (run.t_s[k] - run.t_s[from] < stretch_s && k + 1 < run.size()) continue;
    steps.emplace_back(run.wheel_rad[0][k] - run.wheel_rad[0][from],
                       run.wheel_rad[1][k] - run.wheel_rad[1][from]);
    from = k;
  }
  return steps;
}

// How much the run's turning differs in kind, rows weighted by how far they turned. A run that
// turns only one way (only on the spot, or on one circle) cannot tell a turn-dependent track
// from a track width.
double turn_kind_spread(const RunData& run) {
  return spin_share_spread(wheel_steps(run, 0.0),
                           [](double l, double r) { return std::abs(r - l); });
}

// Whether the run drives one circle: one kind of motion that turns. On a circle of radius R a
// common wheel-radius scale s changes the distance per heading change, which a tracked body
// mounted a lever arm d off the axis shows the same way (its circle has radius R + d, so
// d = (s - 1) R), and a left/right radius difference changes the heading per distance as a
// track width does. With the lever arm fitted, only the track is left to fix; a wheel_radius
// named there comes from the few windows of starting and stopping.
bool drives_one_circle(const std::vector<std::pair<double, double>>& seconds) {
  if (seconds.empty() || motion_kind_spread(seconds) >= kMinSpinShareSpread) return false;
  double turn = 0.0;
  double travel = 0.0;
  for (const auto& [l, r] : seconds) {
    turn += std::abs(r - l);
    travel += std::abs(l) + std::abs(r);
  }
  // Turning in a tenth of the wheel travel or more (a circle under about ten track widths
  // across): a straight run fixes a common radius scale whatever its lever arm.
  if (!(travel > 0.0 && turn >= 0.1 * travel)) return false;
  // Arcs that bend both ways are two circles: a lever arm beside the axis widens one and
  // narrows the other, while a radius scale changes both alike, so they fix the radii. Spins on
  // the spot (more turn than roll) have no side to bend to and are left out.
  double left_bends = 0.0;
  double right_bends = 0.0;
  for (const auto& [l, r] : seconds) {
    if (std::abs(r + l) < std::abs(r - l)) continue;
    ((r - l) * (r + l) > 0.0 ? left_bends : right_bends) += std::abs(r - l);
  }
  return std::min(left_bends, right_bends) < kMinOtherWayShare * (left_bends + right_bends);
}

}  // namespace swivel::model_gap
