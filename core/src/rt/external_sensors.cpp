// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/external_sensors.hpp"

#include <cmath>

namespace swivel::rt {

std::string validate(const SensorWatchOptions& options, const char* what) {
  if (!options.enabled) return "";
  if (!std::isfinite(options.max_age_s) || !(options.max_age_s > 0.0)) {
    return std::string(what) + ": max_age_s must be finite and positive, got " +
           std::to_string(options.max_age_s);
  }
  if (!std::isfinite(options.startup_grace_s) || options.startup_grace_s < 0.0) {
    return std::string(what) + ": startup_grace_s must be finite and not negative, got " +
           std::to_string(options.startup_grace_s);
  }
  if (options.stale_detail[0] == '\0' || options.silent_detail[0] == '\0') {
    return std::string(what) + ": the stale and silent fault causes must not be empty";
  }
  return "";
}

}  // namespace swivel::rt
