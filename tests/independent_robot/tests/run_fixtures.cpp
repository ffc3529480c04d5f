// SPDX-License-Identifier: Apache-2.0
#include "run_fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace swivel::independent::test {

double count_rad() { return 2.0 * std::numbers::pi / 4096.0; }

RunSpec quiet_run(Robot robot, double duration_s, std::vector<TourSegment> tour) {
  RunSpec spec;
  spec.robot = robot;
  spec.duration_s = duration_s;
  spec.noise = NoiseSpec::quiet();
  spec.tour = std::move(tour);
  spec.start_pose = Pose{};
  return spec;
}

std::vector<TourSegment> step_tour(double start_s, const Twist& target) {
  return {TourSegment{0.0, 0.0, Twist{}}, TourSegment{start_s, 0.0, target}};
}

std::vector<const RunRow*> rows_between(const RunRecord& record, double from_s, double to_s) {
  std::vector<const RunRow*> out;
  for (const RunRow& r : record.rows) {
    if (r.t_s >= from_s && r.t_s < to_s) out.push_back(&r);
  }
  return out;
}

const RunRow& row_at(const RunRecord& record, double t_s) {
  const auto it = std::lower_bound(record.rows.begin(), record.rows.end(), t_s,
                                   [](const RunRow& r, double t) { return r.t_s < t; });
  return it == record.rows.end() ? record.rows.back() : *it;
}

double wheel_at(const RunRecord& record, std::size_t i, double t_s) {
  const auto& rows = record.rows;
  if (t_s <= rows.front().t_s) return rows.front().wheel_rad[i];
  const auto it = std::lower_bound(rows.begin(), rows.end(), t_s,
                                   [](const RunRow& r, double t) { return r.t_s < t; });
  if (it == rows.end()) return rows.back().wheel_rad[i];
  const RunRow& b = *it;
  const RunRow& a = *(it - 1);
  const double f = (t_s - a.t_s) / (b.t_s - a.t_s);
  return a.wheel_rad[i] + f * (b.wheel_rad[i] - a.wheel_rad[i]);
}

double wrapped(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

}  // namespace swivel::independent::test
