// SPDX-License-Identifier: Apache-2.0
// Built as if against a Swivel whose Localization declared a virtual method before update():
// every type the same size, update() one vtable slot further on. The loader must refuse it
// and name the method, before the host calls update() through the wrong slot.
#include <array>
#include <cstring>

#include "test_localization.hpp"

namespace {

const SwivelAbiFingerprint* update_moved() {
  static std::array<SwivelAbiVirtual, 64> virtuals{};
  static SwivelAbiFingerprint fingerprint{};
  const SwivelAbiFingerprint& real = *swivel::abi_fingerprint();
  fingerprint = real;
  for (std::uint32_t i = 0; i < real.virtual_count && i < virtuals.size(); ++i) {
    virtuals[i] = real.virtuals[i];
    if (std::strcmp(virtuals[i].method, "Localization::update") == 0) virtuals[i].slot += 1;
  }
  fingerprint.virtuals = virtuals.data();
  return &fingerprint;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) const SwivelPluginDescriptor*
swivel_plugin_descriptor(void) {
  static const SwivelPluginDescriptor descriptor{
      SWIVEL_PLUGIN_ABI_VERSION,
      SWIVEL_PLUGIN_LOCALIZATION,
      "vtable_mismatch",
      [](const char** /*error*/) -> void* {
        return static_cast<swivel::Localization*>(new swivel::test_plugins::TestLocalization());
      },
      [](void* instance) { delete static_cast<swivel::Localization*>(instance); },
      update_moved()};
  return &descriptor;
}
