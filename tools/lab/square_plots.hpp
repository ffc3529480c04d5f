// SPDX-License-Identifier: Apache-2.0
#pragma once
// The plots of `swivel-lab reproduce square` (gnuplot, PNG): the traced square runs
// (Fig. 13 of docs/methods.md §1) and the spread of the change over the calibration seeds.

#include <filesystem>

#include "square_study.hpp"
#include "square_summary.hpp"

namespace swivel::lab {

/// The paper's Table 5 changes, marked on the spread plot (fractions).
struct PaperChanges {
  double position = 0.0;
  double heading = 0.0;
};

/// DIR/square.png: the commanded square and the true paths of the traced runs of the
/// design values, the true values and the first calibrated model.
/// @throws std::runtime_error when gnuplot fails.
void plot_square_runs(const std::filesystem::path& dir, const SquareStudy& study, double side_m);

/// DIR/square_spread.png: the change per calibration seed (one point each) for position
/// and heading, their mean with its standard error, the true values' change and the paper's.
/// @throws std::runtime_error when gnuplot fails.
void plot_square_spread(const std::filesystem::path& dir, const SquareSummary& summary,
                        const PaperChanges& paper);

}  // namespace swivel::lab
