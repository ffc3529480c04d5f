// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <stdexcept>
#include <string>

namespace swivel {

/// A configuration problem found before anything starts. The message names the file,
/// line and key, and what was expected: "swiveld.yaml:12:3: loop.rate_hz: expected a
/// number in [1, 10000], got 'fast'".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace swivel
