// SPDX-License-Identifier: Apache-2.0
// Claims another C++ ABI revision than the host's compiler (as a plugin built with a
// different compiler would): the loader must refuse it before calling into it.
#include "test_localization.hpp"

namespace {

const SwivelAbiFingerprint* other_compiler() {
  static SwivelAbiFingerprint fingerprint = *swivel::abi_fingerprint();
  fingerprint.cxx_abi_version += 1;
  return &fingerprint;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) const SwivelPluginDescriptor*
swivel_plugin_descriptor(void) {
  static const SwivelPluginDescriptor descriptor{
      SWIVEL_PLUGIN_ABI_VERSION,
      SWIVEL_PLUGIN_LOCALIZATION,
      "cxx_abi_mismatch",
      [](const char** /*error*/) -> void* {
        return static_cast<swivel::Localization*>(new swivel::test_plugins::TestLocalization());
      },
      [](void* instance) { delete static_cast<swivel::Localization*>(instance); },
      other_compiler()};
  return &descriptor;
}
