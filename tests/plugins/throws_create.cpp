// SPDX-License-Identifier: Apache-2.0
// Its constructor throws: the host must report the message, not crash.
#include <stdexcept>

#include "test_localization.hpp"

namespace swivel::test_plugins {

class ThrowsInCreate : public TestLocalization {
 public:
  ThrowsInCreate() { throw std::runtime_error("cannot open /dev/imaginary_imu"); }
};

}  // namespace swivel::test_plugins

SWIVEL_EXPORT_PLUGIN(swivel::test_plugins::ThrowsInCreate, swivel::Localization, "throws_create")
