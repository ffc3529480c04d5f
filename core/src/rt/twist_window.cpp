// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/twist_window.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace swivel::rt {
namespace {

using ConstArrayMap = Eigen::Map<const Eigen::ArrayXd>;

bool valid_resolution(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

TwistWindow::TwistWindow(const TwistWindowOptions& options)
    : options_(options), capacity_(options.readings) {
  if (options.readings < 2 || options.readings > kMaxTwistWindowReadings) {
    throw std::invalid_argument("twist window: readings must be in [2, " +
                                std::to_string(kMaxTwistWindowReadings) + "], got " +
                                std::to_string(options.readings));
  }
  if (!valid_resolution(options.wheel_resolution_rad) ||
      !valid_resolution(options.steer_resolution_rad)) {
    throw std::invalid_argument(
        "twist window: encoder resolutions must be finite and >= 0 rad (0: unknown)");
  }
}

void TwistWindow::reset() noexcept {
  count_ = 0;
  next_ = 0;
}

bool TwistWindow::set_resolutions(double wheel_resolution_rad,
                                  double steer_resolution_rad) noexcept {
  if (!valid_resolution(wheel_resolution_rad) || !valid_resolution(steer_resolution_rad)) {
    return false;
  }
  options_.wheel_resolution_rad = wheel_resolution_rad;
  options_.steer_resolution_rad = steer_resolution_rad;
  return true;
}

void TwistWindow::push(const HardwareState& reading) noexcept {
  const std::uint32_t modules = std::min(reading.module_count, kMaxModules);
  if (count_ > 0 && (!(reading.stamp_s > newest_s_) || modules != module_count_)) reset();
  module_count_ = modules;
  const std::size_t slot = next_;
  stamps_[slot] = reading.stamp_s;
  for (std::uint32_t i = 0; i < modules; ++i) {
    channels_[i][slot] = reading.wheel_angle_rad[i];
    // Steering encoders may wrap; a cycle never turns a module by half a turn.
    const double raw = reading.steer_angle_rad[i];
    steer_unwrapped_rad_[i] =
        count_ == 0 ? raw
                    : steer_unwrapped_rad_[i] +
                          std::remainder(raw - last_steer_raw_rad_[i], 2.0 * std::numbers::pi);
    last_steer_raw_rad_[i] = raw;
    channels_[kMaxModules + i][slot] = steer_unwrapped_rad_[i];
  }
  next_ = (next_ + 1) % capacity_;
  count_ = std::min(count_ + 1, capacity_);
  newest_s_ = reading.stamp_s;
  // The oldest reading held: slot 0 until the ring wraps, then the one about to be replaced.
  oldest_s_ = count_ < capacity_ ? stamps_[0] : stamps_[next_];
}

Status TwistWindow::estimate(Drivetrain& drivetrain, TwistEstimate& out) {
  if (count_ < 2) return Status::kError;
  const auto n = static_cast<Eigen::Index>(count_);
  const ConstArrayMap t(stamps_.data(), n);
  const double t_c = t.mean();
  const auto centred = t - t_c;
  const double s_tt = centred.square().sum();
  if (!(s_tt > 0.0) || !std::isfinite(s_tt)) return Status::kError;

  const double h = 0.5 * (newest_s_ - oldest_s_);
  if (!(h > 0.0)) return Status::kError;
  before_ = HardwareState{};
  after_ = HardwareState{};
  before_.stamp_s = t_c - h;
  after_.stamp_s = t_c + h;
  before_.module_count = module_count_;
  after_.module_count = module_count_;
  const auto fit = [&](std::size_t channel) {
    const ConstArrayMap v(channels_[channel].data(), n);
    const double mean = v.mean();
    means_[channel] = mean;
    slopes_[channel] = (centred * (v - mean)).sum() / s_tt;
  };
  for (std::uint32_t i = 0; i < module_count_; ++i) {
    fit(i);
    fit(kMaxModules + i);
    before_.wheel_angle_rad[i] = means_[i] - slopes_[i] * h;
    after_.wheel_angle_rad[i] = means_[i] + slopes_[i] * h;
    before_.steer_angle_rad[i] = means_[kMaxModules + i] - slopes_[kMaxModules + i] * h;
    after_.steer_angle_rad[i] = means_[kMaxModules + i] + slopes_[kMaxModules + i] * h;
  }

  OdometryIncrement increment;
  if (drivetrain.forward(before_, after_, increment) != Status::kOk || !increment.valid) {
    return Status::kError;
  }
  const Eigen::Vector3d twist(increment.twist.vx_mps, increment.twist.vy_mps,
                              increment.twist.wz_radps);

  // Jacobian columns scaled by each rate's standard deviation.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  const auto add_channel = [&](double* before, double* after, double sigma_radps) {
    if (!(sigma_radps > 0.0)) return true;
    const double step = sigma_radps * h;
    *before -= step;
    *after += step;
    OdometryIncrement raised;
    const bool ok = drivetrain.forward(before_, after_, raised) == Status::kOk && raised.valid;
    *before += step;
    *after -= step;
    if (!ok) return false;
    const Eigen::Vector3d column =
        Eigen::Vector3d(raised.twist.vx_mps, raised.twist.vy_mps, raised.twist.wz_radps) - twist;
    covariance.noalias() += column * column.transpose();
    return true;
  };
  const double rate_scale = 1.0 / std::sqrt(12.0 * s_tt);
  const double wheel_sigma = options_.wheel_resolution_rad * rate_scale;
  const double steer_sigma = options_.steer_resolution_rad * rate_scale;
  for (std::uint32_t i = 0; i < module_count_; ++i) {
    if (!add_channel(&before_.wheel_angle_rad[i], &after_.wheel_angle_rad[i], wheel_sigma) ||
        !add_channel(&before_.steer_angle_rad[i], &after_.steer_angle_rad[i], steer_sigma)) {
      return Status::kError;
    }
  }

  out.twist = increment.twist;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      out.covariance[static_cast<std::size_t>(r) * 3 + static_cast<std::size_t>(c)] =
          covariance(r, c);
  }
  out.has_covariance = wheel_sigma > 0.0 || steer_sigma > 0.0;
  out.delay_s = newest_s_ - t_c;
  out.wheel_rate_radps = {};
  out.steer_rate_radps = {};
  for (std::uint32_t i = 0; i < module_count_; ++i) {
    out.wheel_rate_radps[i] = slopes_[i];
    out.steer_rate_radps[i] = slopes_[kMaxModules + i];
  }
  out.readings = static_cast<std::uint32_t>(count_);
  return Status::kOk;
}

}  // namespace swivel::rt
