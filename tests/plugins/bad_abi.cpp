// SPDX-License-Identifier: Apache-2.0
// Declares an ABI version the host does not speak.
#include "test_localization.hpp"

extern "C" __attribute__((visibility("default"))) const SwivelPluginDescriptor*
swivel_plugin_descriptor(void) {
  static const SwivelPluginDescriptor descriptor{
      999U,
      SWIVEL_PLUGIN_LOCALIZATION,
      "bad_abi",
      [](const char** /*error*/) -> void* {
        return static_cast<swivel::Localization*>(new swivel::test_plugins::TestLocalization());
      },
      [](void* instance) { delete static_cast<swivel::Localization*>(instance); },
      swivel::abi_fingerprint()};
  return &descriptor;
}
