// SPDX-License-Identifier: Apache-2.0
#include "swivel/model_gap/noise_model.hpp"

#include <algorithm>
#include <cmath>

namespace swivel::model_gap {

double NoiseModel::sigma(std::size_t c, double x, double known) const {
  return std::sqrt(a[c] + b[c] * x + known);
}

NoiseModel estimate_noise(const std::vector<double>& residuals, std::size_t windows,
                          const std::vector<std::vector<double>>& x,
                          const std::vector<double>& floor_variance,
                          const std::vector<double>& known) {
  const auto known_at = [&known](std::size_t k) { return known.empty() ? 0.0 : known[k]; };
  const std::size_t channels = x.size();
  NoiseModel m;
  m.a.assign(channels, 0.0);
  m.b.assign(channels, 0.0);
  for (std::size_t c = 0; c < channels; ++c) {
    std::vector<double> sq;
    for (std::size_t j = 0; j < windows; ++j) {
      const double r = residuals[c * windows + j];
      if (std::isfinite(r)) sq.push_back(std::max(0.0, r * r - known_at(c * windows + j)));
    }
    double a = floor_variance[c];
    double b = 0.0;
    if (sq.size() >= 4) {
      // Start from the median square (a Gaussian's median square is 0.455 sigma^2).
      auto mid = sq.begin() + static_cast<std::ptrdiff_t>(sq.size() / 2);
      std::nth_element(sq.begin(), mid, sq.end());
      a = std::max(floor_variance[c], *mid / 0.455);
      // Weighted least squares of r^2 on (1, x): the variance of r^2 grows as (a + b x)^2.
      for (int iteration = 0; iteration < 4; ++iteration) {
        double s00 = 0.0;
        double s01 = 0.0;
        double s11 = 0.0;
        double t0 = 0.0;
        double t1 = 0.0;
        for (std::size_t j = 0; j < windows; ++j) {
          const double r = residuals[c * windows + j];
          const double xj = x[c][j];
          if (!std::isfinite(r) || !std::isfinite(xj)) continue;
          const double e = known_at(c * windows + j);
          const double model = a + b * xj;
          const double r2 = r * r - e;
          if (r * r > 16.0 * (model + e)) continue;
          const double w = 1.0 / ((model + e) * (model + e));
          s00 += w;
          s01 += w * xj;
          s11 += w * xj * xj;
          t0 += w * r2;
          t1 += w * r2 * xj;
        }
        const double det = s00 * s11 - s01 * s01;
        double na = s00 > 0.0 ? t0 / s00 : a;
        double nb = 0.0;
        if (det > 1e-12 * s00 * s11 && s11 > 0.0) {
          na = (s11 * t0 - s01 * t1) / det;
          nb = (s00 * t1 - s01 * t0) / det;
        }
        if (nb < 0.0) {
          nb = 0.0;
          na = s00 > 0.0 ? t0 / s00 : a;
        }
        if (na < floor_variance[c]) {
          na = floor_variance[c];
          nb = s11 > 0.0 ? std::max(0.0, (t1 - na * s01) / s11) : 0.0;
        }
        a = na;
        b = nb;
      }
    }
    m.a[c] = std::max(a, floor_variance[c]);
    m.b[c] = std::max(b, 0.0);
  }
  return m;
}

}  // namespace swivel::model_gap
