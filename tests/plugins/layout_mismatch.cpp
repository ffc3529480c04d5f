// SPDX-License-Identifier: Apache-2.0
// Built as if against a Swivel whose HardwareState had grown by 8 bytes: the right ABI
// version, the wrong layout. The loader must refuse it and name the type.
#include <array>

#include "test_localization.hpp"

namespace {

const SwivelAbiFingerprint* grown_hardware_state() {
  static std::array<SwivelAbiLayout, 64> layouts{};
  static SwivelAbiFingerprint fingerprint{};
  const SwivelAbiFingerprint& real = *swivel::abi_fingerprint();
  fingerprint = real;
  for (std::uint32_t i = 0; i < real.layout_count && i < layouts.size(); ++i) {
    layouts[i] = real.layouts[i];
    if (std::string(layouts[i].type) == "HardwareState") layouts[i].size += 8;
  }
  fingerprint.layouts = layouts.data();
  return &fingerprint;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) const SwivelPluginDescriptor*
swivel_plugin_descriptor(void) {
  static const SwivelPluginDescriptor descriptor{
      SWIVEL_PLUGIN_ABI_VERSION,
      SWIVEL_PLUGIN_LOCALIZATION,
      "layout_mismatch",
      [](const char** /*error*/) -> void* {
        return static_cast<swivel::Localization*>(new swivel::test_plugins::TestLocalization());
      },
      [](void* instance) { delete static_cast<swivel::Localization*>(instance); },
      grown_hardware_state()};
  return &descriptor;
}
