// SPDX-License-Identifier: Apache-2.0
#include "square_summary.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "swivel/calibration/swpc_calibration.hpp"
#include "swivel/pose_math.hpp"

namespace swivel::lab {
namespace {

stats::Estimate mean_of(const std::vector<double>& values) {
  return stats::summarize(values).mean_estimate();
}

}  // namespace

EndPoseError end_pose_error(const TrackedModel& tracked) {
  std::vector<stats::Estimate> position;
  std::vector<stats::Estimate> heading;
  for (const bool ccw : {false, true}) {
    std::vector<double> p;
    std::vector<double> h;
    for (const TrackedRun& r : tracked.runs) {
      if (r.counter_clockwise != ccw) continue;
      p.push_back(r.position_error_m);
      h.push_back(r.heading_error_deg);
    }
    if (p.empty()) throw std::invalid_argument("end_pose_error: runs in one direction only");
    position.push_back(mean_of(p));
    heading.push_back(mean_of(h));
  }
  return {stats::average(position), stats::average(heading)};
}

SquareSummary summarize_square(const SquareStudy& study, const RobotModel& truth) {
  if (study.calibrated.empty())
    throw std::invalid_argument("summarize_square: no calibrated model");
  SquareSummary s;
  s.nominal = end_pose_error(study.nominal);
  s.exact = end_pose_error(study.exact);
  s.exact_position_change = stats::relative_change(s.nominal.position_m, s.exact.position_m);
  s.exact_heading_change = stats::relative_change(s.nominal.heading_deg, s.exact.heading_deg);

  std::vector<double> position;
  std::vector<double> heading;
  for (const CalibratedModel& c : study.calibrated) {
    const EndPoseError e = end_pose_error(c.tracked);
    position.push_back(e.position_m.value);
    heading.push_back(e.heading_deg.value);
    s.seed_position_change.push_back(e.position_m.value / s.nominal.position_m.value - 1.0);
    s.seed_heading_change.push_back(e.heading_deg.value / s.nominal.heading_deg.value - 1.0);
  }
  s.calibrated = study.calibrated.size() == 1 ? end_pose_error(study.calibrated.front().tracked)
                                              : EndPoseError{mean_of(position), mean_of(heading)};
  s.position_change = stats::relative_change(s.nominal.position_m, s.calibrated.position_m);
  s.heading_change = stats::relative_change(s.nominal.heading_deg, s.calibrated.heading_deg);
  s.position_spread = stats::summarize(s.seed_position_change);
  s.heading_spread = stats::summarize(s.seed_heading_change);
  for (std::size_t k = 0; k < s.seed_position_change.size(); ++k) {
    s.position_worse += s.seed_position_change[k] > 0.0 ? 1 : 0;
    s.heading_worse += s.seed_heading_change[k] > 0.0 ? 1 : 0;
  }

  s.accuracy.resize(truth.modules.size());
  const auto k = static_cast<double>(study.calibrated.size());
  for (const CalibratedModel& c : study.calibrated) {
    for (std::size_t i = 0; i < truth.modules.size(); ++i) {
      const SwpcModuleParams& e = c.tracked.model.modules.at(i);
      const SwpcModuleParams& t = truth.modules[i];
      ModuleAccuracy& a = s.accuracy[i];
      a.position_mm += (std::pow(e.x_m - t.x_m, 2) + std::pow(e.y_m - t.y_m, 2)) * 1e6 / k;
      a.steering_offset_deg +=
          std::pow(calibration::wrap_pi(e.steering_offset_rad - t.steering_offset_rad) / kRadPerDeg,
                   2) /
          k;
      a.caster_offset_mm += std::pow((e.caster_offset_m - t.caster_offset_m) * 1e3, 2) / k;
      a.wheel_radius_mm += std::pow((e.wheel_radius_m - t.wheel_radius_m) * 1e3, 2) / k;
    }
  }
  for (ModuleAccuracy& a : s.accuracy) {
    a.position_mm = std::sqrt(a.position_mm);
    a.steering_offset_deg = std::sqrt(a.steering_offset_deg);
    a.caster_offset_mm = std::sqrt(a.caster_offset_mm);
    a.wheel_radius_mm = std::sqrt(a.wheel_radius_mm);
  }
  return s;
}

}  // namespace swivel::lab
