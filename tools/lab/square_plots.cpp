// SPDX-License-Identifier: Apache-2.0
#include "square_plots.hpp"

#include <fstream>
#include <string>
#include <vector>

#include "gnuplot.hpp"

namespace swivel::lab {
namespace {

namespace fs = std::filesystem;

void write_trace(const fs::path& file, const std::vector<Pose2>& trace) {
  std::ofstream f(file);
  f << "# x_m y_m (true)\n0 0\n";
  for (const Pose2& p : trace) f << p.x_m << ' ' << p.y_m << '\n';
}

// A short horizontal mark at `y` across category `x` (a gnuplot data block).
void mark(std::ofstream& f, double x, double y) {
  f << x - 0.3 << ' ' << y << '\n' << x + 0.3 << ' ' << y << "\n\n\n";
}

}  // namespace

void plot_square_runs(const fs::path& dir, const SquareStudy& study, double side_m) {
  {
    std::ofstream f(dir / "commanded.dat");
    const double s = side_m;
    f << "0 0\n" << s << " 0\n" << s << ' ' << s << "\n0 " << s << "\n0 0\n\n\n";
    f << "0 0\n" << s << " 0\n" << s << ' ' << -s << "\n0 " << -s << "\n0 0\n";
  }
  struct Series {
    const TrackedModel* tracked;
    const char* name;
    const char* colour;
    const char* title;
  };
  const std::vector<Series> series = {
      {&study.nominal, "nominal", "#d62728", "design values"},
      {&study.exact, "exact", "#2ca02c", "true values (Table 4)"},
      {&study.calibrated.front().tracked, "calibrated", "#1f77b4", "calibrated (first model)"}};
  const fs::path script = dir / "square.gp";
  std::ofstream gp(script);
  gp << "set terminal pngcairo size 1000,1000 font ',11'\n"
     << "set output " << gnuplot_quote(dir / "square.png") << "\n"
     << "set title 'Square tracking on odometry (true paths), CCW above, CW below'\n"
     << "set xlabel 'x [m]'\nset ylabel 'y [m]'\nset size ratio -1\nset grid\n"
     << "set key outside bottom center horizontal\n"
     << "plot " << gnuplot_quote(dir / "commanded.dat")
     << " index 0:1 with lines lw 2 lc rgb 'black' dt 2 title 'commanded'";
  for (const Series& s : series) {
    bool first = true;
    for (const TrackedRun& r : s.tracked->runs) {
      if (r.trace.empty()) continue;
      const fs::path file =
          dir / (std::string(s.name) + "_" + (r.counter_clockwise ? "ccw" : "cw") + "_" +
                 std::to_string(r.index + 1) + ".dat");
      write_trace(file, r.trace);
      gp << ", " << gnuplot_quote(file) << " with lines lc rgb '" << s.colour << "' "
         << (first ? std::string("title '") + s.title + "'" : std::string("notitle"));
      first = false;
    }
  }
  gp << "\n";
  gp.close();
  run_gnuplot(script, "the tables and results.json");
}

void plot_square_spread(const fs::path& dir, const SquareSummary& summary,
                        const PaperChanges& paper) {
  const fs::path data = dir / "square_spread.dat";
  {
    std::ofstream f(data);
    // Block 0: one point per calibration seed, spread across its category by rank.
    f << "# category change_percent\n";
    const std::size_t k = summary.seed_position_change.size();
    for (std::size_t i = 0; i < k; ++i) {
      const double jitter =
          k > 1 ? 0.2 * (static_cast<double>(i) / static_cast<double>(k - 1) - 0.5) : 0.0;
      f << 1.0 + jitter << ' ' << 100.0 * summary.seed_position_change[i] << '\n'
        << 2.0 + jitter << ' ' << 100.0 * summary.seed_heading_change[i] << '\n';
    }
    f << "\n\n";
    // Block 1: mean and standard error.
    f << 1.25 << ' ' << 100.0 * summary.position_change.value << ' '
      << 100.0 * summary.position_change.standard_error << '\n'
      << 2.25 << ' ' << 100.0 * summary.heading_change.value << ' '
      << 100.0 * summary.heading_change.standard_error << "\n\n\n";
    // Blocks 2-3: the true values' change; 4-5: the paper's.
    mark(f, 1.0, 100.0 * summary.exact_position_change.value);
    mark(f, 2.0, 100.0 * summary.exact_heading_change.value);
    mark(f, 1.0, 100.0 * paper.position);
    mark(f, 2.0, 100.0 * paper.heading);
  }
  const fs::path script = dir / "square_spread.gp";
  std::ofstream gp(script);
  const std::string d = gnuplot_quote(data);
  gp << "set terminal pngcairo size 900,700 font ',11'\n"
     << "set output " << gnuplot_quote(dir / "square_spread.png") << "\n"
     << "set title 'Table 5: end-pose error change against the design values, per calibration seed "
        "("
     << summary.seed_position_change.size() << " seeds)'\n"
     << "set ylabel 'change of the end-pose mean absolute error [%]'\n"
     << "set xrange [0.5:2.5]\nset xtics ('position' 1, 'heading' 2)\nset grid ytics\n"
     << "set offsets 0, 0, 5, 5\n"
     << "set key outside bottom center horizontal\n"
     << "plot 0 with lines lc rgb 'gray' dt 2 title 'design values', " << d
     << " index 0 with points pt 7 ps 1.2 lc rgb '#1f77b4' title 'one calibration seed', " << d
     << " index 1 with yerrorbars pt 5 ps 1.5 lc rgb 'black' title 'mean +- standard error', " << d
     << " index 2:3 with lines lw 3 lc rgb '#2ca02c' title 'true values as the model (the bound)', "
     << d << " index 4:5 with lines lw 3 dt 3 lc rgb '#d62728' title 'paper'\n";
  gp.close();
  run_gnuplot(script, "the tables, results.json and square.png");
}

}  // namespace swivel::lab
