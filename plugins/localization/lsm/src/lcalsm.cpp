// SPDX-License-Identifier: Apache-2.0
#include "swivel/localization/lcalsm.hpp"

#include <algorithm>
#include <cmath>

namespace swivel::localization {

LineFit fit_line(const Point2* points, std::size_t count, bool x_of_y) noexcept {
  LineFit fit;
  fit.x_of_y = x_of_y;
  if (points == nullptr || count < 2) return fit;
  const Point2 origin = points[0];
  double su = 0.0;
  double sv = 0.0;
  double suu = 0.0;
  double suv = 0.0;
  for (std::size_t j = 0; j < count; ++j) {
    // u: the abscissa, v: the ordinate of the fitted form v = a u + b.
    const double dx = points[j].x_m - origin.x_m;
    const double dy = points[j].y_m - origin.y_m;
    const double u = x_of_y ? dy : dx;
    const double v = x_of_y ? dx : dy;
    su += u;
    sv += v;
    suu += u * u;
    suv += u * v;
  }
  const auto n = static_cast<double>(count);
  // Cramer's rule on [suu su; su n] [a; b] = [suv; sv].
  const double det = suu * n - su * su;
  if (!(std::abs(det) > 1e-12 * std::max(suu * n, 1e-300))) return fit;
  const double a = (suv * n - su * sv) / det;
  const double b_local = (suu * sv - su * suv) / det;
  const double u0 = x_of_y ? origin.y_m : origin.x_m;
  const double v0 = x_of_y ? origin.x_m : origin.y_m;
  // v - v0 = a (u - u0) + b_local  =>  v = a u + (b_local + v0 - a u0).
  fit.a = a;
  fit.b = b_local + v0 - a * u0;
  fit.ok = std::isfinite(fit.a) && std::isfinite(fit.b);
  return fit;
}

void Lcalsm::configure(const LsmConfig& config) noexcept {
  config_ = config;
  config_.window_points = std::clamp<std::size_t>(config.window_points, 3, kMaxWindowPoints);
  config_.sample_distance_m = std::max(0.0, config.sample_distance_m);
  config_.sample_period_s = std::max(0.0, config.sample_period_s);
  reset();
}

void Lcalsm::reset() noexcept {
  head_ = kMaxWindowPoints - 1;
  held_ = 0;
  stored_ = 0;
  has_last_ = false;
  correction_ = Point2{};
  in_turn_ = false;
  has_segment_ = false;
}

Point2 Lcalsm::point(std::size_t age) const noexcept {
  if (age >= held_) return Point2{};
  return points_[slot(age)];
}

bool Lcalsm::push(const Pose2& eg, double yaw_unwrapped_rad, double distance_m,
                  double stamp_s) noexcept {
  if (!std::isfinite(eg.x_m) || !std::isfinite(eg.y_m) || !std::isfinite(yaw_unwrapped_rad) ||
      !std::isfinite(distance_m) || !std::isfinite(stamp_s)) {
    return false;
  }
  if (has_last_) {
    const bool by_distance = config_.sample_distance_m > 0.0 &&
                             distance_m - last_distance_m_ >= config_.sample_distance_m;
    const bool by_time =
        config_.sample_period_s > 0.0 && stamp_s - last_stamp_s_ >= config_.sample_period_s;
    const bool every_cycle = config_.sample_distance_m == 0.0 && config_.sample_period_s == 0.0;
    if (!by_distance && !by_time && !every_cycle) return false;
  }
  has_last_ = true;
  last_distance_m_ = distance_m;
  last_stamp_s_ = stamp_s;

  head_ = (head_ + 1) % kMaxWindowPoints;
  const Point2 raw{eg.x_m, eg.y_m};
  points_[head_] = raw;
  yaws_[head_] = yaw_unwrapped_rad;
  held_ = std::min(held_ + 1, config_.window_points);
  ++stored_;

  correction_ = Point2{};
  const std::size_t k = config_.window_points;
  in_turn_ = held_ >= 2 && std::abs(yaws_[head_] - yaws_[slot(held_ - 1)]) >
                               config_.max_window_heading_change_rad;
  // heading_aligned: a gentle curve turns too little across one window to be seen as a turn,
  // but it leaves the line the segment set out on; the segment ends there as well.
  const bool left_segment = has_segment_ && std::abs(yaw_unwrapped_rad - anchor_yaw_rad_) >
                                                config_.max_window_heading_change_rad;
  if (in_turn_ || left_segment) has_segment_ = false;
  if (in_turn_) return true;
  if (config_.mode == LsmMode::kPaper) {
    if (held_ == k) compensate_paper();
  } else {
    compensate_heading_aligned(raw, yaw_unwrapped_rad);
  }
  return true;
}

void Lcalsm::compensate_paper() noexcept {
  const std::size_t k = config_.window_points;
  // The window oldest-first in a contiguous copy (k <= 64 points on the stack).
  std::array<Point2, kMaxWindowPoints> window{};
  for (std::size_t j = 0; j < k; ++j) window[j] = points_[slot(k - 1 - j)];
  const double span_x = std::abs(window[k - 1].x_m - window[0].x_m);
  const double span_y = std::abs(window[k - 1].y_m - window[0].y_m);
  const LineFit fit = fit_line(window.data(), k, span_x < span_y);
  if (!fit.ok) return;
  const Point2 raw_newest = points_[head_];
  for (std::size_t j = 0; j < k; ++j) {
    Point2& p = points_[slot(k - 1 - j)];
    if (fit.x_of_y) {
      p.x_m = fit.a * p.y_m + fit.b;
    } else {
      p.y_m = fit.a * p.x_m + fit.b;
    }
  }
  correction_ = Point2{points_[head_].x_m - raw_newest.x_m, points_[head_].y_m - raw_newest.y_m};
}

void Lcalsm::compensate_heading_aligned(const Point2& raw, double yaw_rad) noexcept {
  if (!has_segment_) {
    has_segment_ = true;
    anchor_ = raw;
    anchor_yaw_rad_ = yaw_rad;
    return;
  }
  const double c = std::cos(anchor_yaw_rad_);
  const double s = std::sin(anchor_yaw_rad_);
  const double along_m = (raw.x_m - anchor_.x_m) * c + (raw.y_m - anchor_.y_m) * s;
  const Point2 projected{anchor_.x_m + along_m * c, anchor_.y_m + along_m * s};
  points_[head_] = projected;
  correction_ = Point2{projected.x_m - raw.x_m, projected.y_m - raw.y_m};
}

Pose2 Lcalsm::output(const Pose2& eg_now) const noexcept {
  return Pose2{eg_now.x_m + correction_.x_m, eg_now.y_m + correction_.y_m, eg_now.yaw_rad};
}

}  // namespace swivel::localization
