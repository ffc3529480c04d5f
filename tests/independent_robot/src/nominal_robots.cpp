// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/nominal_robots.hpp"

namespace swivel::independent {

DifferentialGeometry docent_nominal() { return DifferentialGeometry{0.075, 0.075, 0.40}; }

std::array<SwpcModule, 4> swpc4_nominal() {
  constexpr double kX = 0.215;
  constexpr double kY = 0.125;
  constexpr double kD = 0.020;
  constexpr double kR = 0.055;
  return {SwpcModule{kX, kY, 0.0, kD, kR}, SwpcModule{kX, -kY, 0.0, kD, kR},
          SwpcModule{-kX, -kY, 0.0, kD, kR}, SwpcModule{-kX, kY, 0.0, kD, kR}};
}

}  // namespace swivel::independent
