// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/track_by_turn.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

namespace swivel::model_gap {

double turn_radius_m(const RobotModel& nominal, const RunData& run, double window_s) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (nominal.drivetrain != DrivetrainKind::kDifferential || run.wheel_rad.size() != 2 ||
      run.size() < 2 || !(window_s > 0.0)) {
    return kNaN;
  }
  const DifferentialParams& p = nominal.differential;
  double distance_turn = 0.0;
  double turn_squared = 0.0;
  std::size_t a = 0;
  for (std::size_t k = 1; k < run.size(); ++k) {
    if (run.t_s[k] - run.t_s[a] < window_s && k + 1 < run.size()) continue;
    const double left = p.wheel_radius_left_m * (run.wheel_rad[0][k] - run.wheel_rad[0][a]);
    const double right = p.wheel_radius_right_m * (run.wheel_rad[1][k] - run.wheel_rad[1][a]);
    const double distance = 0.5 * (left + right);
    const double turn = (right - left) / p.track_width_m;
    if (std::isfinite(distance) && std::isfinite(turn)) {
      distance_turn += distance * turn;
      turn_squared += turn * turn;
    }
    a = k;
  }
  return turn_squared > 0.0 ? distance_turn / turn_squared : kNaN;
}

TrackByTurn fit_track_by_turn(const std::vector<double>& scales, const std::vector<double>& sigmas,
                              const std::vector<double>& radii_m, double track_width_m) {
  TrackByTurn out;
  const std::size_t n = scales.size();
  std::size_t left = 0;
  std::size_t right = 0;
  Eigen::MatrixXd a(n, 2);
  Eigen::VectorXd y(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    const double w = 1.0 / sigmas[k];
    const double r = std::isfinite(radii_m[k]) ? radii_m[k] : 0.0;
    left += r >= kMinTurnRadiusEachWayM ? 1 : 0;
    right += r <= -kMinTurnRadiusEachWayM ? 1 : 0;
    // s = s0 - (2 R / b) e, whitened.
    a(i, 0) = w;
    a(i, 1) = -w * 2.0 * r / track_width_m;
    y(i) = w * scales[k];
  }
  out.runs = n;
  if (n < 4 || left < 2 || right < 2) return out;
  const Eigen::Matrix2d information = a.transpose() * a;
  const Eigen::Vector2d theta = information.ldlt().solve(a.transpose() * y);
  const Eigen::Matrix2d covariance = information.inverse();
  out.fitted = true;
  out.track_scale = theta(0);
  out.radius_difference = theta(1);
  out.track_scale_sigma = std::sqrt(covariance(0, 0));
  out.radius_difference_sigma = std::sqrt(covariance(1, 1));
  out.chi_square = (y - a * theta).squaredNorm();
  const double mean = a.col(0).dot(y) / a.col(0).squaredNorm();
  out.chi_square_one_track = (y - a.col(0) * mean).squaredNorm();
  return out;
}

}  // namespace swivel::model_gap
