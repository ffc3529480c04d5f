// SPDX-License-Identifier: Apache-2.0
// Named like a localization plugin but declares itself a drivetrain.
#include "test_localization.hpp"

extern "C" __attribute__((visibility("default"))) const SwivelPluginDescriptor*
swivel_plugin_descriptor(void) {
  static const SwivelPluginDescriptor descriptor{SWIVEL_PLUGIN_ABI_VERSION,
                                                 SWIVEL_PLUGIN_DRIVETRAIN,
                                                 "wrong_kind",
                                                 [](const char** error) -> void* {
                                                   *error = "must never be called";
                                                   return nullptr;
                                                 },
                                                 [](void* /*instance*/) {},
                                                 swivel::abi_fingerprint()};
  return &descriptor;
}
